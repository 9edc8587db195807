#!/usr/bin/env bash
# Scale-out benchmarks for docs/notes/scale-out.md: strong scaling of `generate` (one process with 1 and
# 2 threads, MPI with 1 and 2 ranks of 1 thread), whole-process wall time best of N and peak memory
# of the writing process, then the per-brick costs (thread time of each brick kind) on cumulus-field.
# Usage: scripts/bench_scale.sh [REPEATS]   (after building build/bin/cloudgen with MPI)
set -euo pipefail
cd "$(dirname "$0")/.."
reps="${1:-3}"
cg=build/bin/cloudgen
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1   # CI runs as root

# best-of-N wall time of a command; prints "seconds peak_rss_kib" (the largest process of the run)
measure() {
  local best=999999 mem=0
  for _ in $(seq "$reps"); do
    /usr/bin/time -f "%e %M" -o "$tmp/t" "$@" > /dev/null 2> "$tmp/err"
    read -r t m < "$tmp/t"
    best=$(awk -v a="$best" -v b="$t" 'BEGIN{print (b<a)?b:a}')
    mem=$m
  done
  echo "$best $mem"
}

echo "| case | 1 process, 1 thread | 1 process, 2 threads | MPI 1 rank x 1 thread | MPI 2 ranks x 1 thread | speed-up 2 threads / 2 ranks |"
echo "|---|---|---|---|---|---|"
for spec in "cumulus-field::cumulus-field 512x128x512" "thesis:--resolution 256:thesis at 256^3"; do
  IFS=: read -r preset extra label <<< "$spec"
  read -r t1 m1 < <(measure $cg generate "$preset" $extra -q --threads 1 -o "$tmp/o.vdb")
  read -r t2 m2 < <(measure $cg generate "$preset" $extra -q --threads 2 -o "$tmp/o.vdb")
  read -r r1 _ < <(measure mpirun -n 1 $cg generate "$preset" $extra -q --threads 1 -o "$tmp/o.vdb")
  read -r r2 _ < <(measure mpirun -n 2 $cg generate "$preset" $extra -q --threads 1 -o "$tmp/o.vdb")
  printf "| %s | %.2f s, %d MiB | %.2f s | %.2f s | %.2f s | %.2fx / %.2fx |\n" "$label" "$t1" $((m1 / 1024)) "$t2" "$r1" "$r2" \
    "$(awk -v a="$t1" -v b="$t2" 'BEGIN{print a/b}')" "$(awk -v a="$r1" -v b="$r2" 'BEGIN{print a/b}')"
done

echo
echo "Writing rank's memory against the one-process run (peak RSS from --stats):"
for spec in "cumulus-field:" "thesis:--resolution 256"; do
  IFS=: read -r preset extra <<< "$spec"
  $cg generate "$preset" $extra -q --stats --threads 1 -o "$tmp/o.vdb" 2>&1 | sed 's/^/    one process: /'
  mpirun -n 2 $cg generate "$preset" $extra -q --stats --threads 1 -o "$tmp/o.vdb" 2>&1 | sed 's/^/    2 ranks: /'
done

echo
echo "Per-brick costs on cumulus-field, one rank, one thread (the plan's bound is the 'plan' time):"
mpirun -n 1 $cg generate cumulus-field -q --stats --threads 1 -o "$tmp/o.vdb" 2>&1 | sed 's/^/    /'
