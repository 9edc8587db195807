#!/usr/bin/env bash
# The README's first command: install what is missing, build, and run the main job on the default
# preset: a VDB for Blender, an RGBA 3D texture for game engines and a preview picture, in out/.
source "$(dirname "$0")/common.sh"
install_missing scripts/packages.txt
configure_and_build -DCLOUD_BUILD_TESTS=OFF -DCLOUD_BUILD_BENCH=OFF
mkdir -p out
if [ -x build/bin/cloudgen ] && [ -f presets/cumulus.json ]; then
  log "cloudgen generate presets/cumulus.json -> out/cumulus.vdb, out/cumulus.raw"
  build/bin/cloudgen generate presets/cumulus.json -o out/cumulus.vdb -o out/cumulus.raw
  build/bin/cloudgen info out/cumulus.vdb
  if [ -x build/bin/cloudviewer ]; then
    log "cloudviewer preview -> out/cumulus.png"
    build/bin/cloudviewer out/cumulus.vdb --headless --size 640x360 --out out/cumulus.png
  fi
else
  log "noise bake -> out/noise.raw"
  build/bin/cloudgen noise --kind perlin-worley --period 4 --octaves 4 --seed 1 --size 64 -o out/noise.raw
fi
log "done: $(ls out | tr '\n' ' ')"
