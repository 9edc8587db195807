#!/usr/bin/env bash
# cloudgen benchmarks: wall time and peak memory of `generate` with brick skipping on and off, and
# VDB float vs half (file size, max error). Prints markdown tables for docs/benchmarks.md.
# Usage: scripts/bench_cloudgen.sh [REPEATS]   (after scripts/run.sh or scripts/test.sh built build/)
set -euo pipefail
cd "$(dirname "$0")/.."
reps="${1:-3}"
cg="${CLOUDGEN:-build/bin/cloudgen}"   # CLOUDGEN=other/binary compares builds in the same run
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT

# best-of-N wall time and peak RSS of one command
measure() {
  local best=999999 mem=0
  for _ in $(seq "$reps"); do
    /usr/bin/time -f "%e %M" -o "$tmp/t" "$@" >/dev/null 2>&1
    read -r t m < "$tmp/t"
    best=$(awk -v a="$best" -v b="$t" 'BEGIN{print (b<a)?b:a}')
    mem=$m
  done
  echo "$best $mem"
}

echo "| case | output | skipping on: time, peak RSS | skipping off: time | speed-up |"
echo "|---|---|---|---|---|"
for spec in "thesis::thesis 128^3" "thesis:--resolution 256:thesis at 256^3" "cumulus-field::cumulus-field 512x128x512"; do
  IFS=: read -r preset extra label <<< "$spec"
  read -r t_on m_on < <(measure $cg generate "$preset" $extra -q -o "$tmp/o.vdb")
  read -r t_off _ < <(measure $cg generate "$preset" $extra -q --no-skip -o "$tmp/o.vdb")
  printf "| %s | .vdb | %.2f s, %d MiB | %.2f s | %.2fx |\n" "$label" "$t_on" $((m_on / 1024)) "$t_off" \
    "$(awk -v a="$t_off" -v b="$t_on" 'BEGIN{print a/b}')"
done

echo
echo "| preset | VDB float | VDB half | size ratio | max abs error (half vs float) |"
echo "|---|---|---|---|---|"
for preset in thesis cumulus-field; do
  $cg generate "$preset" -q -o "$tmp/f.vdb"
  $cg generate "$preset" -q --set export.vdb.half=true -o "$tmp/h.vdb"
  err=$(/usr/bin/python3 - "$tmp/f.vdb" "$tmp/h.vdb" <<'PY'
import sys, numpy as np, pyopenvdb as vdb
f = vdb.read(sys.argv[1], "density"); h = vdb.read(sys.argv[2], "density")
(lo, hi) = f.evalActiveVoxelBoundingBox()
shape = tuple(hi[i] - lo[i] + 1 for i in range(3))
a = np.zeros(shape, np.float32); b = np.zeros(shape, np.float32)
f.copyToArray(a, ijk=lo); h.copyToArray(b, ijk=lo)
print(f"{np.abs(a - b).max():.2e}")
PY
)
  sf=$(stat -c %s "$tmp/f.vdb"); sh=$(stat -c %s "$tmp/h.vdb")
  printf "| %s | %.1f MiB | %.1f MiB | %.2f | %s |\n" "$preset" "$(awk -v s=$sf 'BEGIN{print s/1048576}')" \
    "$(awk -v s=$sh 'BEGIN{print s/1048576}')" "$(awk -v a=$sh -v b=$sf 'BEGIN{print a/b}')" "$err"
done
