#!/usr/bin/env bash
# docs/notes/nanovdb.md: frame time of render.volume=dense against =nanovdb on the thesis preset, issue
# 13's outside and below views, 320x180, one llvmpipe thread. The storage is not a bench
# configuration (the volume is prepared once per process), so the two run in alternating
# processes, ROUNDS times each, and the best frame of each counts (the machine is shared).
# Both read the same thesis.nvdb (dense: densified, the same box and image); nanovdb runs twice,
# with the GPU's default lookup (render.nanovdb_lookup=atlas) and with the page table. Prints one
# line per view; the logs stay in OUT_DIR.
# Usage: scripts/bench_nanovdb.sh [OUT_DIR] [ROUNDS] [SIZE]   (needs build/bin/cloudgen and cloudviewer)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/nanovdb}"
rounds="${2:-3}"
size="${3:-320x180}"
mkdir -p "$out"
build/bin/cloudgen generate thesis -o "$out/thesis.nvdb" -o "$out/thesis.vdb" -o "$out/thesis.raw" --quiet
for view in outside below; do
  extra=()
  [ "$view" = below ] && extra=(--set render.max_distance=2133)
  for r in $(seq "$rounds"); do
    for run in dense nanovdb table; do
      storage=(--set render.volume=nanovdb)
      [ "$run" = dense ] && storage=(--set render.volume=dense)
      [ "$run" = table ] && storage+=(--set render.nanovdb_lookup=table)
      LP_NUM_THREADS=1 build/bin/cloudviewer "$out/thesis.nvdb" --headless --size "$size" \
        --bench "bench/tracks/nanovdb_$view.json" --sun 135,35.26 --set render.ground_height=-341.33 \
        "${extra[@]}" "${storage[@]}" --bench-repeat 2 >"$out/$view-$run-$r.txt" 2>&1
    done
  done
  best() { grep -h '^this storage' "$out/$view-$1-"*.txt | awk '{print $3}' | sort -g | head -1; }
  gpu() { grep -ho '[0-9.]* MiB on the GPU' "$out/$view-$1-1.txt" | head -1; }
  d=$(best dense) n=$(best nanovdb) t=$(best table)
  echo "$view: dense $d ms ($(gpu dense)), nanovdb (atlas) $n ms, nanovdb (table) $t ms ($(gpu nanovdb)), atlas/dense $(awk "BEGIN{printf \"%.2f\", $n/$d}"), table/dense $(awk "BEGIN{printf \"%.2f\", $t/$d}")"
done
