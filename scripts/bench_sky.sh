#!/usr/bin/env bash
# Frame cost of the three skies, measured in the same run with the settings interleaved (analytic,
# march, LUT, repeated) so load changes on a shared machine hit all three alike: the GPU timer of
# the second frame (no LUT pass) of `cloudviewer --headless --frames 2 --fps 0 --stats`, best of N,
# for a box-mode view of synthetic:blob, a layer-mode view of synthetic:noise and a view of the sky
# and the ground alone; and the first frame's 4D scattering LUT pass. Ratios are against the
# analytic sky and, for the LUT, against the march.
# Usage: scripts/bench_sky.sh [REPEATS] [SIZE]   (default 3, 320x180; EGL, llvmpipe without a GPU)
set -euo pipefail
reps="${1:-3}"; size="${2:-320x180}"
here="$(cd "$(dirname "$0")/.." && pwd)"
viewer="${CLOUDVIEWER:-$here/build/bin/cloudviewer}"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
for _ in $(seq "$reps"); do
  for sky in analytic march lut; do
    case $sky in
      analytic) s=(render.sky=analytic) ;;
      march) s=(render.sky=precomputed render.sky_lut=false) ;;
      lut) s=(render.sky=precomputed render.sky_lut=true) ;;
    esac
    for view in box layer sky; do
      case $view in
        box) args=(synthetic:blob --sun 0,30) ;;
        layer) args=(synthetic:noise --sun 0,30 --set render.mode=layer render.adaptive=true) ;;
        sky) args=(synthetic:blob --camera 0,2,0:0,30,100 --sun 0,30) ;;
      esac
      "$viewer" "${args[@]}" --headless --size "$size" --frames 2 --fps 0 --stats --out "$tmp/m.png" \
        --set "${s[@]}" > "$tmp/log" 2>&1
      total=$(grep -E '^frame 1 .*gpu: [0-9]+x[0-9]+ total' "$tmp/log" | sed -E 's/.* total ([0-9.]+) ms.*/\1/')
      lut=$(grep -E '^frame 0 .*gpu passes' "$tmp/log" | sed -E 's/.*atmosphere_scattering ([0-9.e-]+) ms.*/\1/')
      echo "$sky $view $total $lut" >> "$tmp/t"
    done
  done
done
/usr/bin/python3 - "$tmp/t" "$size" "$reps" <<'PY'
import sys
rows = {}
lut_pass = []
for line in open(sys.argv[1]):
    sky, view, total, lut = line.split()
    rows.setdefault((sky, view), []).append(float(total))
    if sky == "lut":
        lut_pass.append(float(lut))
print(f"| view ({sys.argv[2]}, best of {sys.argv[3]}, frame 1) | analytic | march | LUT | march / analytic | LUT / analytic | LUT / march |")
print("|---|---:|---:|---:|---:|---:|---:|")
for view in ("box", "layer", "sky"):
    a, m, l = (min(rows[(s, view)]) for s in ("analytic", "march", "lut"))
    print(f"| {view} | {a:.0f} ms | {m:.0f} ms | {l:.0f} ms | {m / a:.2f} | {l / a:.2f} | {l / m:.2f} |")
print(f"\n4D scattering LUT pass (frame 0): best {min(lut_pass):.0f} ms, worst {max(lut_pass):.0f} ms over {len(lut_pass)} runs")
PY
