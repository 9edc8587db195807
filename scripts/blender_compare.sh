#!/usr/bin/env bash
# Side by side for docs/blender.md: the viewer's default view of a preset's VDB and the Cycles render
# of the scene `cloudgen blender` makes from the same file, plus how well they agree (cloud masks'
# IoU and bounding boxes in pixels, mean luminance of the cloud pixels).
# Usage: scripts/blender_compare.sh PRESET OUT_DIR [WxH] [SAMPLES]   (run from the repository root
# after building build/bin/cloudgen and build/bin/cloudviewer)
set -euo pipefail
preset="$1"; out="$2"; size="${3:-320x180}"; samples="${4:-64}"
bin=build/bin
mkdir -p "$out"
"$bin/cloudgen" generate "$preset" -q -o "$out/$preset.vdb"
"$bin/cloudviewer" "$out/$preset.vdb" --headless --size "$size" --out "$out/${preset}_viewer.png" >/dev/null
"$bin/cloudviewer" "$out/$preset.vdb" --headless --size "$size" --out "$out/${preset}_viewer_t.png" \
  --set render.output=transmittance render.tonemap=clamp render.exposure=1 render.bloom=0 >/dev/null
"$bin/cloudgen" blender "$out/$preset.vdb" -q -o "$out/$preset.blend" --render "$out/${preset}_cycles.png" \
  --size "$size" --samples "$samples"
run() { blender -b --factory-startup --python-exit-code 1 --python tests/blender_roundtrip.py -- "$@" 2>&1 |
  grep -E "^(cloud pixels|bounding box|viewer:|cycles:|masks|IoU|Error)" || true; }
run mask "$out/$preset.blend" "$out/${preset}_cycles_mask.png" >/dev/null
run compare "$out/${preset}_viewer_t.png" "$out/${preset}_cycles_mask.png" "$out/${preset}_viewer.png" "$out/${preset}_cycles.png"
ls -l "$out/${preset}_viewer.png" "$out/${preset}_cycles.png" | awk '{print $5, $9}'
