#!/usr/bin/env bash
# Every benchmark in one command (a few minutes on 2 cores), after scripts/run.sh or test.sh built
# build/: libnoise3d (Google Benchmark), cloudgen (generate + export), the viewer's speed knobs on a
# short camera track, the fBm octave count and half-float VDBs. Rewrites the tables of
# docs/benchmarks.md and draws one run-time-against-error plot per speed knob into docs/images/.
# Usage: scripts/bench.sh [--quick]   (--quick: fewer repetitions, smaller images; for a smoke run)
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0; [ "${1:-}" = "--quick" ] && quick=1
reps=3; size=160x90; ref=1024; [ $quick = 1 ] && reps=1 size=96x54 ref=512
for b in build/bin/bench_noise build/bin/cloudgen build/bin/cloudviewer; do
  [ -x "$b" ] || { echo "bench.sh: $b is missing; run scripts/test.sh (or scripts/run.sh) first" >&2; exit 2; }
done
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
stamp="$(date -u +%Y-%m-%d) on $(nproc) cores ($(uname -m)), load $(cut -d' ' -f1 /proc/loadavg) at the start"
log() { printf '\033[1m==> %s\033[0m\n' "$*" >&2; }

log "libnoise3d: Google Benchmark, $reps repetitions"
build/bin/bench_noise --benchmark_repetitions=$reps 2>/dev/null | grep '^BM_' > /tmp/bench_noise.txt
log "cloudgen: generate + export, best of $reps"
bash scripts/bench_cloudgen.sh $reps > /tmp/bench_cloudgen.md
/usr/bin/python3 scripts/update_bench_docs.py "$stamp with scripts/bench.sh"

log "viewer knobs: thesis preset, $size, CPU reference at $ref steps"
build/bin/cloudgen generate thesis -q -o "$work/thesis.raw"
build/bin/cloudviewer "$work/thesis.raw" --headless --size "$size" --bench bench/tracks/knobs.json \
  --bench-repeat $reps --bench-reference $ref --csv "$work/viewer.csv" > "$work/viewer.txt"
build/bin/cloudviewer "$work/thesis.raw" --headless --size "$size" --bench bench/tracks/light_samples.json \
  --set render.light_samples=64 --bench-repeat $reps --csv "$work/light.csv" > "$work/light.txt"

log "fBm octaves: time and error against 10 octaves"
for o in 1 2 3 4 5 6 8 10; do
  /usr/bin/time -f "%e" -o "$work/t" build/bin/cloudgen noise --kind perlin-worley --period 4 --octaves $o \
    --size 96 --threads 1 --seed 9 -o "$work/oct$o.raw" 2>/dev/null
  echo "$o $(cat "$work/t")" >> "$work/octaves.txt"
done

log "VDB float vs half: size, write time, error"
for h in false true; do
  /usr/bin/time -f "%e" -o "$work/t" build/bin/cloudgen generate thesis -q --set export.vdb.half=$h -o "$work/h$h.vdb"
  echo "$h $(cat "$work/t") $(stat -c %s "$work/h$h.vdb")" >> "$work/half.txt"
done

log "plots and tables"
/usr/bin/python3 scripts/bench_plots.py "$work" "$stamp"
log "done: docs/benchmarks.md and docs/images/bench_*.png updated"
