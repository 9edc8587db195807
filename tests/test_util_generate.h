// Test helpers that generate (cloudgen/generate.h), for the test files of the cloudgen library.
#pragma once

#include <gtest/gtest.h>

#include "cloudgen/generate.h"
#include "test_util.h"

namespace testutil {

/// Generates `p` with skipping, without it, on one thread and on two, expects the same density
/// bytes from all four (and the same first detail channel skipped or not), and returns the skipped
/// run's volume with its stats in `stats`.
inline cloudgen::Volume generate_every_way(const cloudgen::Preset& p, cloudgen::GenerateStats& stats) {
  cloudgen::GenerateOptions on, off, one, two;
  off.skip_empty = false;
  one.threads = 1, two.threads = 2;
  cloudgen::Volume a = cloudgen::generate(p, on, &stats);
  const cloudgen::Volume b = cloudgen::generate(p, off), c = cloudgen::generate(p, one), d = cloudgen::generate(p, two);
  EXPECT_TRUE(same_bytes(a.density, b.density)) << "skipped and unskipped runs differ";
  EXPECT_TRUE(same_bytes(a.detail[0], b.detail[0])) << "skipped and unskipped runs differ in detail";
  EXPECT_TRUE(same_bytes(c.density, d.density)) << "one and two threads differ";
  EXPECT_TRUE(same_bytes(a.density, c.density)) << "the default and one thread differ";
  return a;
}

}  // namespace testutil
