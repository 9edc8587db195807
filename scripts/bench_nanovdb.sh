#!/usr/bin/env bash
# docs/nanovdb.md: frame time of render.volume=dense against =nanovdb on the thesis preset, issue
# 13's outside and below views, 320x180, one llvmpipe thread, best of REPEAT rounds (default 3).
# Usage: scripts/bench_nanovdb.sh [OUT_DIR] [REPEAT]   (needs build/bin/cloudgen and cloudviewer)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/nanovdb}"
repeat="${2:-3}"
mkdir -p "$out"
build/bin/cloudgen generate thesis -o "$out/thesis.nvdb" -o "$out/thesis.vdb" -o "$out/thesis.raw" --quiet
common=(--headless --size 320x180 --sun 135,35.26 --set render.ground_height=-341.33 --bench-repeat "$repeat")
for view in outside below; do
  extra=()
  [ "$view" = below ] && extra=(--set render.max_distance=2133)
  for volume in dense nanovdb; do
    for input in thesis.nvdb thesis.vdb thesis.raw; do
      [ "$volume" = dense ] && [ "$input" != thesis.raw ] && continue  # one dense run: the same texture
      log="$out/$view-$volume-${input#thesis.}.txt"
      LP_NUM_THREADS=1 build/bin/cloudviewer "$out/$input" --bench "bench/tracks/nanovdb_$view.json" \
        "${common[@]}" "${extra[@]}" --set render.volume=$volume >"$log" 2>&1
      ms=$(awk '/^this storage/ {print $3}' "$log")
      gpu=$(grep -o '[0-9.]* MiB on the GPU' "$log" | head -1)
      echo "$view $volume $input frame_ms=$ms gpu=$gpu"
    done
  done
done
