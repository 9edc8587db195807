#!/usr/bin/env bash
# Brick-skipping speed-up of two cloudgen builds, measured in the same run with the runs
# interleaved (A skip, A no-skip, B skip, B no-skip, repeated), so load changes on a shared machine
# hit both builds alike. Reports per build the best-of-N whole-process wall time and the median
# CPU time (user + sys) of `generate PRESET -o x.vdb` with and without --no-skip, and their ratios.
# Usage: scripts/bench_skip_ab.sh OLD_CLOUDGEN NEW_CLOUDGEN [PRESET] [REPEATS] [extra generate args]
set -euo pipefail
a="$1"; b="$2"; preset="${3:-thesis}"; reps="${4:-7}"; shift 4 2>/dev/null || shift $#
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
for _ in $(seq "$reps"); do
  for bin in a b; do
    exe=$a; [[ $bin == b ]] && exe=$b
    for mode in skip noskip; do
      flag=""; [[ $mode == noskip ]] && flag="--no-skip"
      /usr/bin/time -f "$bin $mode %e %U %S" -a -o "$tmp/t" "$exe" generate "$preset" "$@" -q $flag -o "$tmp/o.vdb" > /dev/null 2>&1
    done
  done
done
/usr/bin/python3 - "$tmp/t" "$a" "$b" "$preset $*" <<'PY'
import sys, statistics as st
rows = {}
for line in open(sys.argv[1]):
    who, mode, wall, user, sys_ = line.split()
    rows.setdefault((who, mode), []).append((float(wall), float(user) + float(sys_)))
print(f"| build ({sys.argv[4].strip()}) | skip: best wall, median CPU | no-skip: best wall, median CPU | speed-up wall / CPU |")
print("|---|---|---|---|")
for who, name in (("a", sys.argv[2]), ("b", sys.argv[3])):
    s, n = rows[(who, "skip")], rows[(who, "noskip")]
    sw, sc = min(w for w, _ in s), st.median(c for _, c in s)
    nw, nc = min(w for w, _ in n), st.median(c for _, c in n)
    print(f"| {name} | {sw:.2f} s, {sc:.2f} s | {nw:.2f} s, {nc:.2f} s | {nw / sw:.2f}x / {nc / sc:.2f}x |")
PY
