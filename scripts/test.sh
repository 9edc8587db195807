#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run the whole test suite:
# unit tests (noise, cloudgen, viewer on Mesa llvmpipe), the Blender round trip, an ASan+UBSan
# build of the unit tests, and a short libFuzzer run on the preset reader. One ctest summary.
source "$(dirname "$0")/common.sh"
install_missing scripts/packages.txt scripts/packages-test.txt
jobs="$(nproc)"

log "building the libFuzzer targets (clang) into build-fuzz/"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCLOUD_FUZZ=ON -DCLOUD_BUILD_CLOUDGEN=ON -DCLOUD_BUILD_VIEWER=ON -DCLOUD_BUILD_TESTS=OFF -DCLOUD_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz -j "$jobs" --target fuzz_preset fuzz_cli fuzz_raw fuzz_ktx2 fuzz_vdb fuzz_nvdb fuzz_track fuzz_viewer_input

log "building the ASan+UBSan unit tests into build-asan/"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCLOUD_SANITIZE=ON \
  -DCLOUD_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j "$jobs" --target cloud_tests cloudgen

configure_and_build -DCLOUD_BUILD_TESTS=ON -DCLOUD_BUILD_BENCH=ON \
  -DCLOUD_ASAN_TESTS="$ROOT/build-asan/bin/cloud_tests" -DCLOUD_FUZZ_BIN_DIR="$ROOT/build-fuzz/bin"
log "running the test suite (ctest)"
cd build
ctest --output-on-failure -j "$jobs" --timeout 900
