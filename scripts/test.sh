#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run the whole test suite:
# unit tests (noise, cloudgen, viewer on Mesa llvmpipe), the Blender round trip, the unit tests
# again built with clang's ASan+UBSan, and short libFuzzer runs on every reader. One ctest summary.
# docs/notes/testing.md has the time each part takes and why the suite is laid out this way.
source "$(dirname "$0")/common.sh"
install_missing scripts/packages.txt scripts/packages-test.txt
jobs="$(nproc)"
clang_build() {  # DIR, then cmake options
  local dir="$1"
  shift
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCLOUD_BUILD_CLOUDGEN=ON -DCLOUD_BUILD_VIEWER=ON -DCLOUD_BUILD_BENCH=OFF "$@" >/dev/null
}

# The unit tests under ASan+UBSan (clang), without the fuzzer's coverage instrumentation, which
# would double their time; cloudgen too, since the tests run it.
log "building the ASan+UBSan unit tests (clang) into build-asan/"
clang_build build-asan -DCLOUD_SANITIZE=ON -DCLOUD_BUILD_TESTS=ON
cmake --build build-asan -j "$jobs" --target cloud_tests cloudgen

log "building the libFuzzer targets (clang, ASan+UBSan) into build-fuzz/"
clang_build build-fuzz -DCLOUD_FUZZ=ON -DCLOUD_BUILD_TESTS=OFF
cmake --build build-fuzz -j "$jobs" --target fuzz_preset fuzz_cli fuzz_raw fuzz_ktx2 fuzz_vdb fuzz_nvdb fuzz_weather fuzz_plan fuzz_pack fuzz_mesh \
  fuzz_track fuzz_viewer_input

configure_and_build -DCLOUD_BUILD_TESTS=ON -DCLOUD_BUILD_BENCH=ON \
  -DCLOUD_ASAN_TESTS="$ROOT/build-asan/bin/cloud_tests" -DCLOUD_FUZZ_BIN_DIR="$ROOT/build-fuzz/bin"
log "running the test suite (ctest)"
cd build
ctest --output-on-failure -j "$jobs" --timeout 900
