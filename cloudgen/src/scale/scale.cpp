// Scale-out helpers that need neither OpenVDB nor MPI: balancing a plan, tile checksums.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>

#include "cloudgen/scale.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/printable.h"

namespace cloudgen {

std::vector<std::vector<size_t>> balance_bricks(const BrickPlan& plan, int parts) {
  if (parts < 1) throw InputError("balance: need at least one part, got " + std::to_string(parts));
  std::vector<size_t> order(plan.bricks.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return plan.bricks[a].cost > plan.bricks[b].cost; });
  std::vector<double> load(static_cast<size_t>(parts), 0.0);
  std::vector<std::vector<size_t>> out(static_cast<size_t>(parts));
  for (size_t b : order) {
    const size_t r = size_t(std::min_element(load.begin(), load.end()) - load.begin());
    load[r] += plan.bricks[b].cost;
    out[r].push_back(b);
  }
  for (auto& o : out) std::sort(o.begin(), o.end());
  return out;
}

std::string file_checksum(const std::string& path) {
  protect_input(path, "the input " + printable(path));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot read");
  uint64_t h = 0xcbf29ce484222325ull;
  std::vector<char> buf(1 << 20);
  uint64_t at = 0;
  bool vdb = false;
  // OpenVDB writes a fresh random UUID into every file (36 characters at byte 21, after the magic,
  // three version words and a flag byte); everything else of a cloudgen VDB is deterministic.
  // Leaving the UUID out makes a regenerated tile's checksum equal the original's.
  constexpr uint64_t kUuidAt = 21, kUuidEnd = 21 + 36;
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const std::streamsize n = in.gcount();
    if (at == 0 && n >= 4) vdb = std::memcmp(buf.data(), " BDV", 4) == 0;
    for (std::streamsize i = 0; i < n; ++i, ++at) {
      if (vdb && at >= kUuidAt && at < kUuidEnd) continue;
      h = (h ^ uint8_t(buf[size_t(i)])) * 0x100000001b3ull;
    }
  }
  if (in.bad()) throw IoError(path + ": read failed");
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

}  // namespace cloudgen
