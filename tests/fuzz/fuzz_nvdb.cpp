// libFuzzer target for the .nvdb reader (cloudgen::parse_nvdb) and what the viewer does with an
// accepted file: the dense copy (under a 64 MiB budget), the occupancy from the leaves and the
// accessor lookups the renderers make. Each input is read twice: as is, and with every grid's
// checksum switched off, so mutations reach the structure checks behind the checksum.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "cloudgen/nvdb.h"
#include "fuzz_common.h"

namespace {

// The file layout (nanovdb::io): a 16-byte header (grid count at byte 12), per grid a 176-byte
// descriptor (grid size at 0, name size at 136) and its name, then the grids; a grid's checksum
// is its bytes 8..15 (all ones: none).
std::vector<uint8_t> without_checksums(const uint8_t* data, size_t size) {
  std::vector<uint8_t> b(data, data + size);
  if (size < 16) return b;
  uint16_t count = 0;
  std::memcpy(&count, &b[12], 2);
  size_t pos = 16;
  std::vector<uint64_t> sizes;
  for (uint16_t g = 0; g < count && g < 64; ++g) {
    if (size - pos < 176) return b;
    uint64_t gs = 0;
    uint32_t ns = 0;
    std::memcpy(&gs, &b[pos], 8);
    std::memcpy(&ns, &b[pos + 136], 4);
    sizes.push_back(gs);
    if (ns > size - pos - 176) return b;
    pos += 176 + ns;
  }
  for (uint64_t gs : sizes) {
    if (size - pos < 16) break;
    std::memset(&b[pos + 8], 0xff, 8);
    if (gs > size - pos) break;
    pos += size_t(gs);
  }
  return b;
}

void exercise(const uint8_t* data, size_t size) {
  fuzz::guarded([&] {
    const cloudgen::NanoVolume n = cloudgen::parse_nvdb(data, size, "fuzz.nvdb");
    // The occupancy of a box up to 2^31 voxels (a work budget, as the dense copy's below): a
    // mutation that turns on a 4096^3 root tile makes a valid 10^10-voxel volume, whose occupancy
    // is correct but takes over libFuzzer's 10 s under ASan (found from the quantised seeds, whose
    // decoded box is the content's; a float file's is the one it stores).
    if (uint64_t(n.dims[0]) * n.dims[1] * n.dims[2] <= (uint64_t(1) << 31)) {
      std::array<uint32_t, 3> od{};
      const std::vector<uint8_t> occ = cloudgen::nano_occupancy(n, 8, 2, od);
      if (occ.size() != size_t(od[0]) * od[1] * od[2]) __builtin_trap();
    }
    for (size_t g = 0; g < n.grids.size(); ++g)
      for (int k = 0; k < 64; ++k) {
        const std::array<int32_t, 3> ijk{n.index_min[0] + int32_t(n.dims[0] * (k & 3) / 3),
                                         n.index_min[1] + int32_t(n.dims[1] * ((k >> 2) & 3) / 3),
                                         n.index_min[2] + int32_t(n.dims[2] * (k >> 4) / 3)};
        (void)cloudgen::nano_value(n, g, ijk);
      }
    const cloudgen::Volume v = cloudgen::dense_from_nano(n, uint64_t(64) << 20, "fuzz.nvdb");
    if (v.density.size() != v.voxel_count()) __builtin_trap();
    for (float f : v.density)
      if (!std::isfinite(f)) __builtin_trap();
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  exercise(data, size);
  const std::vector<uint8_t> b = without_checksums(data, size);
  exercise(b.data(), b.size());
  return 0;
}
