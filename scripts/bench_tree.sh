#!/usr/bin/env bash
# docs/notes/nanovdb.md, render.skipping=tree (issue 13's hierarchical DDA through the NanoVDB tree):
# frame time and loop trips per pixel of no skipping, the distance field and the tree's empty
# nodes, on the thesis views (bench/tracks/nanovdb_tree.json) and on the sparse cumulus-field
# (nanovdb_tree_field.json), the clouds still and moving (--time 60), render.volume=nanovdb,
# one llvmpipe thread. Every table's max|diff| column is against no skipping.
# Usage: scripts/bench_tree.sh [OUT_DIR] [SIZE]   (needs build/bin/cloudgen and cloudviewer)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/tree}"
size="${2:-320x180}"
mkdir -p "$out"
build/bin/cloudgen generate thesis -o "$out/thesis.nvdb" --quiet
build/bin/cloudgen generate cumulus-field -o "$out/field.nvdb" --quiet
echo "Measured $(date -u +%Y-%m-%d) on $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg) at the start, with \`scripts/bench_tree.sh\`, ${size}, LP_NUM_THREADS=1, best of 2:"
for time in 0 60; do
  for run in thesis field; do
    track=bench/tracks/nanovdb_tree.json extra=(--sun 135,35.26)
    [ "$run" = field ] && track=bench/tracks/nanovdb_tree_field.json extra=()
    echo
    echo "$run, --time $time:"
    LP_NUM_THREADS=1 build/bin/cloudviewer "$out/$run.nvdb" --headless --size "$size" --bench "$track" "${extra[@]}" \
      --set render.volume=nanovdb --time "$time" --bench-repeat 2 >"$out/$run-$time.txt" 2>&1
    sed -n '/^configuration/,/^(frame/p' "$out/$run-$time.txt" | sed '$d'
  done
done
