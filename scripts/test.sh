#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run the whole test suite.
source "$(dirname "$0")/common.sh"
install_missing scripts/packages.txt scripts/packages-test.txt
configure_and_build -DCLOUD_BUILD_TESTS=ON -DCLOUD_BUILD_BENCH=ON
log "running the test suite (ctest)"
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 900
