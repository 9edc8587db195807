// Parsers for command-line values shared by cloudgen's commands and the viewer: strict (no
// trailing text, no silent wrap-around), finite, range-checked, with errors that name the flag,
// the value and what is allowed. Fuzzed by tests/fuzz/fuzz_cli.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cloudgen {

/// Most worker threads any command accepts (0 = all cores).
inline constexpr int kMaxThreads = 1024;

/// A decimal integer in [0, max] with nothing else around it ("-1", "1e3", "7x" are refused).
uint64_t parse_uint(const std::string& s, const std::string& flag, uint64_t max);

/// "X,Y,Z:W,H,D": origin and extent in voxels, each extent >= 1, the box inside `dims`.
struct Region {
  std::array<uint32_t, 3> origin{{0, 0, 0}}, extent{{0, 0, 0}};
};
Region parse_region(const std::string& s, const std::array<uint32_t, 3>& dims, const std::string& flag = "--region");

/// Comma-separated finite numbers; exactly n1 or n3 of them.
std::vector<double> parse_number_list(const std::string& s, const std::string& flag, size_t n1, size_t n3);

/// "2G", "512M", "64K", "1000000" (bytes); positive, below 2^62.
uint64_t parse_bytes(const std::string& s, const std::string& flag);

}  // namespace cloudgen
