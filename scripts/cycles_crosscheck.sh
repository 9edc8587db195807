#!/usr/bin/env bash
# The path tracer (`cloudviewer --backend pathtrace`) against Blender's Cycles, an independent
# renderer, on one scene (docs/notes/accuracy.md, issue 10): cumulus at 96 voxels, the default view, lit
# by the sun alone (no sky light, no ground, the analytic sky's constant sun colour), HG g 0.3,
# albedo 1. Cycles renders the scene `cloudgen blender` writes, re-lit by scripts/cycles_crosscheck.py
# (black world, transparent film), twice with two seeds; the path tracer's cloud radiance is its
# image minus the transmittance times the background. Prints the two means and their ratio.
# Usage: scripts/cycles_crosscheck.sh [WxH] [PT_SPP] [CYCLES_SAMPLES] [BOUNCES] [STEP_RATE] [MAX_DIFF]
#   (after scripts/test.sh; CLOUD_BIN names the binaries' folder, default build/bin). With MAX_DIFF
#   (e.g. 0.03) it exits 1 when the two means differ by more than that fraction (the ctest check).
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-128x72}"; spp="${2:-512}"; samples="${3:-256}"; bounces="${4:-64}"; rate="${5:-1}"; max="${6:-}"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
bin="${CLOUD_BIN:-build/bin}"
light=(--set render.sky=analytic --set render.ambient=0 --set render.ground=false --set render.bloom=0
       --set render.albedo=1 --set render.phase=hg --set render.g=0.3)
"$bin/cloudgen" generate cumulus -q --resolution 96 -o "$work/c.vdb"
"$bin/cloudviewer" "$work/c.vdb" "${light[@]}" --lighting-json "$work/sun.json" > /dev/null
"$bin/cloudgen" blender "$work/c.vdb" -q -o "$work/c.blend" --size "$size"
t0=$(date +%s)
"$bin/cloudviewer" "$work/c.vdb" --headless --size "$size" "${light[@]}" --backend pathtrace --spp "$spp" \
  --out "$work/pt.exr" > /dev/null 2> "$work/pt.log"
t1=$(date +%s)
"$bin/cloudviewer" "$work/c.vdb" --headless --size "$size" "${light[@]}" --set render.density=0 --out "$work/bg.exr" > /dev/null
"$bin/cloudviewer" "$work/c.vdb" --headless --size "$size" "${light[@]}" --set render.output=transmittance \
  --set render.steps=1024 --out "$work/t.exr" > /dev/null
bl() { blender -b --python-exit-code 1 --python scripts/cycles_crosscheck.py -- "$@" 2>&1; }
for s in 0 1; do
  bl render "$work/c.blend" "$work/cy$s.exr" "$samples" "$bounces" "$s" "$work/sun.json" "$rate" | grep -E "^Error|Traceback" || true
done
t2=$(date +%s)
echo "cumulus 96 voxels, $size, path tracer $spp spp ($((t1 - t0)) s), Cycles $samples samples x 2 seeds, $bounces volume bounces, step rate $rate ($((t2 - t1)) s)"
out="$(bl compare "$work/pt.exr" "$work/bg.exr" "$work/t.exr" "$work/cy0.exr" "$work/cy1.exr" $max)" || { echo "$out"; exit 1; }
echo "$out" | grep -E "^(cloud|mean|noise|FAIL)|Error|Traceback"
if echo "$out" | grep -q "^FAIL"; then exit 1; fi
