// libFuzzer target for the KTX2 reader (header, level index, key/value data, texels).
#include <cmath>
#include <cstdint>
#include <vector>

#include "cloudgen/io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> bytes(data, data + size);
  return fuzz::guarded([&] {
    cloudgen::Volume v = cloudgen::parse_ktx2(bytes, "fuzz.ktx2", uint64_t(64) << 20);
    if (v.density.size() != v.voxel_count() || v.occupancy.empty()) __builtin_trap();
    for (float f : v.density)
      if (!std::isfinite(f)) __builtin_trap();
  });
}
