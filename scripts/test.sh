#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run the whole test suite:
# unit tests (noise, cloudgen, viewer on Mesa llvmpipe), the Blender round trip, the unit tests
# again built with clang's ASan+UBSan, and short libFuzzer runs on every reader. One ctest summary.
source "$(dirname "$0")/common.sh"
install_missing scripts/packages.txt scripts/packages-test.txt
jobs="$(nproc)"

# One clang build with ASan + UBSan (and libFuzzer's coverage) serves both the fuzz targets and the
# sanitizer run of the unit tests, so the sources compile twice, not three times.
log "building the libFuzzer targets and the ASan+UBSan unit tests (clang) into build-fuzz/"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCLOUD_FUZZ=ON -DCLOUD_BUILD_CLOUDGEN=ON -DCLOUD_BUILD_VIEWER=ON -DCLOUD_BUILD_TESTS=ON -DCLOUD_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz -j "$jobs" --target fuzz_preset fuzz_cli fuzz_raw fuzz_ktx2 fuzz_vdb fuzz_nvdb fuzz_track \
  fuzz_viewer_input cloud_tests cloudgen

configure_and_build -DCLOUD_BUILD_TESTS=ON -DCLOUD_BUILD_BENCH=ON \
  -DCLOUD_ASAN_TESTS="$ROOT/build-fuzz/bin/cloud_tests" -DCLOUD_FUZZ_BIN_DIR="$ROOT/build-fuzz/bin"
log "running the test suite (ctest)"
cd build
ctest --output-on-failure -j "$jobs" --timeout 900
