// Occupancy structure (thesis 2.4.2): a coarse grid that encloses every non-zero voxel, dilated by
// `padding` coarse cells so a large step just under one cell cannot cut a corner and miss cloud.
#include <algorithm>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cloudgen/volume.h"

namespace cloudgen {

void dilate_occupancy(std::vector<uint8_t>& raw, const std::array<uint32_t, 3>& od, uint32_t padding, bool tiles_xz) {
  // Separable dilation by `padding` cells per axis (a box dilation: the union over the
  // (2p+1)^3 neighbourhood), wrapping in x and z for tiling volumes. A cell takes the first
  // non-zero neighbour value in the order d = -p .. p. Whole runs of `stride` cells move together
  // (one line of cells per neighbour offset), so no cell divides its index into coordinates.
  const int pad = int(padding);
  std::vector<uint8_t> tmp(raw.size());
  for (int a = 0; a < 3; ++a) {
    const bool wrap = tiles_xz && a != 1;
    const int n = int(od[a]);
    const size_t stride = a == 0 ? 1 : a == 1 ? od[0] : size_t(od[0]) * od[1];
    const size_t outer = n > 0 ? raw.size() / (size_t(n) * stride) : 0;
    // Each outer index writes its own run of tmp: the runs go to all cores.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, outer), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t o = r.begin(); o != r.end(); ++o)
      for (int c = 0; c < n; ++c) {
        uint8_t* dst = &tmp[(o * n + c) * stride];
        std::fill(dst, dst + stride, uint8_t(0));
        for (int d = -pad; d <= pad; ++d) {
          int q = c + d;
          if (wrap) q = ((q % n) + n) % n;
          else if (q < 0 || q >= n) continue;
          const uint8_t* src = &raw[(o * n + size_t(q)) * stride];
          for (size_t k = 0; k < stride; ++k)
            if (!dst[k]) dst[k] = src[k];
        }
      }
    });
    raw.swap(tmp);
  }
}

std::vector<uint8_t> occupancy_cells(const float* density, const std::array<uint32_t, 3>& dims, uint32_t cell,
                                     uint32_t padding, bool tiles_xz, std::array<uint32_t, 3>& od) {
  const uint32_t c = std::max<uint32_t>(1, cell);
  for (int a = 0; a < 3; ++a) od[a] = (dims[a] + c - 1) / c;
  const size_t ncells = size_t{od[0]} * od[1] * od[2];
  std::vector<uint8_t> raw(ncells, 0);
  // One slab of cells (c voxel planes in z) per task: no two tasks write the same cell.
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, od[2]), [&](const tbb::blocked_range<uint32_t>& slabs) {
    for (uint32_t z = slabs.begin() * c; z < std::min(dims[2], slabs.end() * c); ++z)
      for (uint32_t y = 0; y < dims[1]; ++y) {
        const float* row = density + (size_t(z) * dims[1] + y) * dims[0];
        uint8_t* orow = &raw[(size_t(z / c) * od[1] + y / c) * od[0]];
        for (uint32_t x = 0; x < dims[0]; ++x)
          if (row[x] > 0) orow[x / c] = 1;
      }
  });
  dilate_occupancy(raw, od, padding, tiles_xz);
  return raw;
}

void build_occupancy(Volume& v) {
  std::array<uint32_t, 3> od{};
  v.occupancy = occupancy_cells(v.density.data(), v.dims, v.occupancy_cell, v.occupancy_padding, v.tiles_xz, od);
  v.occupancy_dims = od;
}

}  // namespace cloudgen
