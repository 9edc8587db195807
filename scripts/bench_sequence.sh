#!/usr/bin/env bash
# Cost of baking a motion sequence (`cloudgen generate --frames`), per frame, against the static
# export of the same preset measured in the same run: wall time of the static run (generate +
# write one .vdb) and of a 24-frame run, and cloudgen's own split of a frame into displacement
# and VDB write. Prints a markdown table for docs/notes/motion.md.
# Usage: scripts/bench_sequence.sh [THREADS]   (after building build/bin/cloudgen)
set -euo pipefail
cd "$(dirname "$0")/.."
threads="${1:-0}"
cg="${CLOUDGEN:-build/bin/cloudgen}"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
frames=24

echo "| preset (voxels) | static run (generate + 1 .vdb) | $frames-frame run | per frame: displace, write | frame / static run |"
echo "|---|---|---|---|---|"
for spec in "tiny:32^3" "cumulus:128x64x128" "thesis:128^3" "thesis --resolution 256:256^3"; do
  IFS=: read -r preset label <<< "$spec"
  # shellcheck disable=SC2086
  /usr/bin/time -f "%e" -o "$tmp/t0" $cg generate $preset -q --threads "$threads" -o "$tmp/static.vdb"
  # shellcheck disable=SC2086
  /usr/bin/time -f "%e" -o "$tmp/t1" $cg generate $preset -q --stats --threads "$threads" --frames 1:$frames --fps 24 \
    -o "$tmp/seq/c_####.vdb" 2> "$tmp/log"
  t0=$(tail -1 "$tmp/t0"); t1=$(tail -1 "$tmp/t1")
  disp=$(grep -o 'displace [0-9.]* s' "$tmp/log" | awk '{print $2}')
  write=$(grep -o 'write [0-9.]* s' "$tmp/log" | tail -1 | awk '{print $2}')
  per=$(awk -v a="$t1" -v b="$t0" -v n="$frames" 'BEGIN{printf "%.3f", (a-b)/n}')
  printf "| %s (%s) | %.2f s | %.2f s | %s s, %s s | %.2f |\n" "${preset%% *}" "$label" "$t0" "$t1" "$disp" "$write" \
    "$(awk -v p="$per" -v b="$t0" 'BEGIN{print p/b}')"
  rm -rf "$tmp/seq"
done
echo
echo "(measured $(date -u +%Y-%m-%d) on $(nproc) cores, --threads $threads; frame = (sequence run - static run) / $frames)"
