#!/usr/bin/env bash
# The octaves against the path tracer in display space (docs/notes/accuracy.md, issue 10): for the cumulus and
# thesis presets at their default views, the path tracer (`--backend pathtrace`, two seeds of
# SPP paths per pixel: their mean is the reference, their difference its noise) against the CPU
# reference of the marcher at render.ms_octaves = 1..4, RMSE of the display image and mean
# brightness; and the picture docs/notes/accuracy.md shows. Bloom off, so pixels compare one to one.
# Usage: scripts/accuracy_octaves.sh [SPP] [WxH]   (default 128, 160x90; after scripts/test.sh built build/)
set -euo pipefail
cd "$(dirname "$0")/.."
spp="${1:-128}"; size="${2:-160x90}"
for b in build/bin/cloudgen build/bin/cloudviewer; do
  [ -x "$b" ] || { echo "accuracy_octaves.sh: $b is missing; run scripts/test.sh first" >&2; exit 2; }
done
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
v=build/bin/cloudviewer
for p in cumulus thesis; do
  build/bin/cloudgen generate "$p" -q -o "$work/$p.raw"
  for seed in 0 1; do
    /usr/bin/time -f "%e" -o "$work/$p.pt$seed.s" $v "$work/$p.raw" --headless --size "$size" --backend pathtrace \
      --spp "$spp" --set render.bloom=0 --set render.frame=$seed --out "$work/$p.pt$seed.png" > /dev/null 2>&1
  done
  for o in 1 2 3 4; do
    /usr/bin/time -f "%e" -o "$work/$p.o$o.s" $v "$work/$p.raw" --headless --size "$size" --backend cpu \
      --set render.bloom=0 --set render.ms_octaves=$o --out "$work/$p.o$o.png" > /dev/null
  done
done
/usr/bin/python3 - "$work" "$spp" "$size" <<'PY'
import os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as im, numpy as np
w, spp, size = sys.argv[1], sys.argv[2], sys.argv[3]
read = lambda n: im.imread(os.path.join(w, n))[..., :3].astype(np.float64)
rmse = lambda a, b: float(np.sqrt(((a - b) ** 2).mean()))
secs = lambda n: float(open(os.path.join(w, n)).read().split()[-1])
print("| preset | ms_octaves | RMSE vs path tracer | mean brightness / path tracer's | CPU reference s |")
print("|---|---:|---:|---:|---:|")
rows = []
for p in ("cumulus", "thesis"):
    a, b = read(p + ".pt0.png"), read(p + ".pt1.png")
    ref = (a + b) / 2
    for o in (1, 2, 3, 4):
        c = read("%s.o%d.png" % (p, o))
        print("| %s | %d | %.4f | %.3f | %.2f |" % (p, o, rmse(c, ref), c.mean() / ref.mean(), secs("%s.o%d.s" % (p, o))))
    print("| %s | path tracer, %s spp | noise %.4f | 1 | %.1f |" % (p, spp, rmse(a, b) / 2, secs(p + ".pt0.s")))
    rows.append(np.concatenate([read(p + ".o1.png"), read(p + ".o4.png"), ref], axis=1))
gap = np.ones((4, rows[0].shape[1], 3))
out = "docs/images/accuracy_octaves.png"
im.imsave(out + ".tmp.png", np.concatenate([rows[0], gap, rows[1]], axis=0))
os.replace(out + ".tmp.png", out)
print()
print("Noise: half the RMSE between the two seeds' images, the noise of their mean. Size %s." % size)
PY
