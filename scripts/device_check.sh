#!/usr/bin/env bash
# The GPU figures issues 11 and 13 ask for, in one run on a lent machine (the device tool's `run`,
# in the repository root, with .device from scripts/device_bundle.sh and, where the machine has no
# libEGL, .gl from the device README in `carry`):
#   bash scripts/device_check.sh            every step, about 7-9 minutes; use timeout_s 590
#   SIZE_SMALL=320x180 SIZE_LARGE=480x270 OUT=/tmp/o bash scripts/device_check.sh
#                                           the same steps on this machine's llvmpipe, to try the script
# Each step has its own time limit, so one that hangs costs its limit, not the run. Results go to
# $OUT (at most 8 files come back): summary.txt (the machine, each step's exit code and seconds),
# steps.log (every step's output), outside.png and the CSVs (compute_<size>.csv,
# temporal_compute_<size>.csv, temporal_<size>.csv, thesis_<size>.csv, moving_<size>.csv), packed
# into csv.tar after the last step. Steps run most wanted first: when the run's limit cuts the
# last ones, the CSVs the first wrote still come back (six at most then).
set -uo pipefail
cd "$(dirname "$0")/.."
OUT="${OUT:?OUT: the folder results go to}"
SMALL="${SIZE_SMALL:-1280x720}" LARGE="${SIZE_LARGE:-1920x1080}"
mkdir -p "$OUT"
summary="$OUT/summary.txt" steps="$OUT/steps.log"
: > "$summary"; : > "$steps"
note() { echo "$*" | tee -a "$summary"; }

b="$(mktemp -d)"
tar -xJf .device/bundle.tar.xz -C "$b" || { note "no .device/bundle.tar.xz: run scripts/device_bundle.sh and carry .device"; exit 1; }
export LD_LIBRARY_PATH="$b/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
if ! ldconfig -p | grep -q 'libEGL.so.1 ' && [[ -d .gl ]]; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
nv=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[[ -f $nv ]] && export __EGL_VENDOR_LIBRARY_FILENAMES="$nv"
# The NVIDIA driver's EGL answered on the surfaceless platform on the H200 (2026-12-04), not on the
# device platform; CLOUDVIEWER_EGL from the caller wins.
export CLOUDVIEWER_EGL="${CLOUDVIEWER_EGL:-surfaceless}"
{ date -u; uname -srm; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "no nvidia-smi"; nproc; } >> "$summary"

# step NAME LIMIT_S COMMAND...: runs one step under its limit, output to steps.log.
step() {
  local name="$1" limit="$2" t0 rc
  shift 2
  t0="$(date +%s%N)"
  echo "=== $name: $*" >> "$steps"
  timeout --kill-after=5 "$limit" "$@" >> "$steps" 2>&1
  rc=$?
  local ms=$(( ($(date +%s%N) - t0) / 1000000 ))
  note "$(printf '%-14s rc=%-3s %4d.%01d s (limit %s s)' "$name" "$rc" $((ms / 1000)) $((ms % 1000 / 100)) "$limit")"
}
vol="$b/vol"
mkdir -p "$vol"
step volumes 60 bash -c "'$b/bin/cloudgen' generate thesis -q -o '$vol/thesis.raw' && '$b/bin/cloudgen' generate cumulus -q -o '$vol/cumulus.raw'"
view=(--sun 135,35.26 --camera 1280,1600,-2200:1280,500,1280 --set render.ground_height=-341.33)
# A first process: the driver compiles and caches the shaders; its time is the cold start.
step first_frame 90 "$b/bin/cloudviewer" "$vol/thesis.raw" --headless --size "$SMALL" "${view[@]}" --out "$OUT/outside.png"
# render.compute first (2026-12-06): the cloud pass as a compute shader against the full-screen
# triangle, the same image; the H100/H200 shade pixels on two of their TPCs only.
step compute_large 100 "$b/bin/cloudviewer" "$vol/thesis.raw" --headless --size "$LARGE" --sun 135,35.26 \
  --bench bench/tracks/compute_gpu.json --bench-repeat 3 --csv "$OUT/compute_$LARGE.csv"
step temporal_cs 100 "$b/bin/bench_temporal" "$vol/cumulus.raw" --size "$LARGE" --repeat 3 --frames 16 \
  --set render.compute=true --csv "$OUT/temporal_compute_$LARGE.csv"
step temporal_large 120 "$b/bin/bench_temporal" "$vol/cumulus.raw" --size "$LARGE" --repeat 3 --frames 16 \
  --csv "$OUT/temporal_$LARGE.csv"
step thesis_small 150 "$b/bin/cloudviewer" "$vol/thesis.raw" --headless --size "$SMALL" --sun 135,35.26 \
  --bench bench/tracks/thesis_gpu.json --bench-repeat 3 --csv "$OUT/thesis_$SMALL.csv"
step thesis_large 150 "$b/bin/cloudviewer" "$vol/thesis.raw" --headless --size "$LARGE" --sun 135,35.26 \
  --bench bench/tracks/thesis_gpu.json --bench-repeat 3 --csv "$OUT/thesis_$LARGE.csv"
# Moving clouds (--time 60): the moved grid's distance field and the light volume rebuilt per frame.
step moving_large 100 "$b/bin/cloudviewer" "$vol/thesis.raw" --headless --size "$LARGE" --sun 135,35.26 --time 60 \
  --bench bench/tracks/moving_gpu.json --bench-repeat 3 --csv "$OUT/moving_$LARGE.csv"
(cd "$OUT" && tar -cf csv.tar ./*.csv && rm -f ./*.csv)
rm -rf "$b"
