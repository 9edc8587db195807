// libFuzzer target for the raw texture reader: the input is a sidecar's JSON text, a NUL byte,
// then the texel bytes, optionally a second NUL-separated block with occupancy bytes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "cloudgen/io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const uint8_t* end = data + size;
  const uint8_t* nul = std::find(data, end, uint8_t(0));
  const std::string sidecar(reinterpret_cast<const char*>(data), size_t(nul - data));
  std::vector<uint8_t> texels, occupancy;
  if (nul != end) texels.assign(nul + 1, end);
  // Once without an occupancy file, once with the texel bytes standing in for one.
  for (const std::vector<uint8_t>* occ : {&occupancy, &texels})
    fuzz::guarded([&] {
      // 64 MiB: the reader must refuse larger claims before allocating
      cloudgen::Volume v = cloudgen::parse_raw(sidecar, texels, "fuzz.raw", occ, uint64_t(64) << 20);
      if (v.density.size() != v.voxel_count() || v.occupancy.empty()) __builtin_trap();
      for (float f : v.density)
        if (!std::isfinite(f)) __builtin_trap();
    });
  return 0;
}
