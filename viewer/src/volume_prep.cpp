// Densifying: a cloudgen::Volume into the interleaved RGBA floats and the occupancy grid both
// renderers sample, with the memory it needs estimated first.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/nvdb.h"
#endif

namespace cloudviewer {
namespace {

std::string number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string gib(uint64_t bytes) {
  std::ostringstream os;
  os.precision(3);
  os << double(bytes) / double(uint64_t(1) << 30) << " GiB";
  return os.str();
}

// The occupancy grid of `density` (x fastest) through cloudgen's one builder.
void occupancy_from(PreparedVolume& p, int occ_cell, int occ_padding, std::vector<float> density) {
  cloudgen::Volume g;
  for (int i = 0; i < 3; ++i) g.dims[size_t(i)] = uint32_t(p.dims[size_t(i)]);
  g.tiles_xz = p.tiles;
  g.occupancy_cell = uint32_t(occ_cell);
  g.occupancy_padding = uint32_t(occ_padding);
  g.density = std::move(density);
  cloudgen::build_occupancy(g);
  p.occ_cell = occ_cell;
  p.occ_padding = occ_padding;
  for (int i = 0; i < 3; ++i) p.occ_dims[size_t(i)] = int(g.occupancy_dims[size_t(i)]);
  p.occ = std::move(g.occupancy);
}

void finish_occupancy(PreparedVolume& p) {
  size_t count = 0;
  for (uint8_t o : p.occ) count += o ? 1 : 0;
  p.occupied_fraction = p.occ.empty() ? 0 : double(count) / double(p.occ.size());
}

}  // namespace

uint64_t prepared_bytes(uint64_t voxels) { return voxels * 16 + voxels / 8; }

uint64_t available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  uint64_t kb = 0;
  while (in >> key >> kb) {
    if (key == "MemAvailable:") return kb * 1024;
    in.ignore(1 << 10, '\n');
  }
  long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? uint64_t(pages) * uint64_t(size) : UINT64_MAX;
}

void check_memory(const std::string& what, uint64_t bytes) {
  const uint64_t available = available_memory_bytes();
  if (bytes > available)
    throw InputError(what + ": needs about " + gib(bytes) + " of memory to render, " + gib(available) +
                     " is available (use a smaller resolution)");
}

PreparedVolume prepare_volume(const cloudgen::Volume& v, int occ_cell, int occ_padding) {
  PreparedVolume p;
  for (int i = 0; i < 3; ++i) {
    if (v.dims[size_t(i)] > 4096)
      throw InputError("volume dimension " + std::to_string(v.dims[size_t(i)]) + " exceeds 4096");
    p.dims[size_t(i)] = int(v.dims[size_t(i)]);
  }
  size_t n = v.voxel_count();
  if (n == 0 || v.density.empty())
    throw InputError("volume has no density channel (not a cloud volume)");
  if (v.density.size() != n)
    throw InputError("volume density has " + std::to_string(v.density.size()) + " values, dims say " +
                     std::to_string(n));
  if (!(v.voxel_size > 0) || !std::isfinite(v.voxel_size) || v.voxel_size > 1e5)
    throw InputError("volume voxel size " + number(v.voxel_size) + " m: must be a finite number in (0, 1e5] metres");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v.origin[size_t(i)]) || std::abs(v.origin[size_t(i)]) > 1e8)
      throw InputError("volume origin " + number(v.origin[size_t(i)]) + " m: must be finite, |x| <= 1e8 m");
  check_memory("volume " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]),
               prepared_bytes(n));
  p.voxel_size = v.voxel_size;
  p.origin = glm::dvec3(v.origin[0], v.origin[1], v.origin[2]);
  p.tiles = v.tiles_xz;
  p.has_detail = true;
  for (int c = 0; c < 3; ++c) {
    if (!v.detail[size_t(c)].empty() && v.detail[size_t(c)].size() != n)
      throw InputError("volume detail channel " + std::to_string(c) + " has the wrong size");
    if (v.detail[size_t(c)].empty()) p.has_detail = false;
  }
  p.rgba.assign(n * 4, 0.f);
  for (size_t i = 0; i < n; ++i) {
    float d = v.density[i];
    if (!std::isfinite(d)) throw InputError("volume density has a non-finite value at voxel " + std::to_string(i));
    p.rgba[i * 4] = std::max(d, 0.f);
    for (int c = 0; c < 3; ++c) p.rgba[i * 4 + 1 + size_t(c)] = v.detail[size_t(c)].empty() ? 0.f : v.detail[size_t(c)][i];
  }
  // The volume's own grid when it was built for this cell and padding over these dims (cloudgen
  // builds it with the same function); otherwise build it here.
  bool reuse = !v.occupancy.empty() && int(v.occupancy_cell) == occ_cell && int(v.occupancy_padding) == occ_padding;
  for (int i = 0; i < 3 && reuse; ++i)
    reuse = v.occupancy_dims[size_t(i)] == (v.dims[size_t(i)] + uint32_t(occ_cell) - 1) / uint32_t(occ_cell);
  reuse = reuse && v.occupancy.size() == size_t(v.occupancy_dims[0]) * v.occupancy_dims[1] * v.occupancy_dims[2];
  if (reuse) {
    p.occ_cell = occ_cell;
    p.occ_padding = occ_padding;
    for (int i = 0; i < 3; ++i) p.occ_dims[size_t(i)] = int(v.occupancy_dims[size_t(i)]);
    p.occ.assign(v.occupancy.begin(), v.occupancy.end());
    for (uint8_t& o : p.occ) o = o ? 1 : 0;
  } else {
    std::vector<float> density(n);
    for (size_t i = 0; i < n; ++i) density[i] = p.rgba[i * 4];
    occupancy_from(p, occ_cell, occ_padding, std::move(density));
  }
  finish_occupancy(p);
  return p;
}

void build_occupancy(PreparedVolume& p, int occ_cell, int occ_padding) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (p.nano) {  // the nanovdb path: from the grid's leaves and tiles, no dense copy
    std::array<uint32_t, 3> od{};
    p.occ = cloudgen::nano_occupancy(*p.nano, uint32_t(occ_cell), uint32_t(occ_padding), od);
    p.occ_cell = occ_cell;
    p.occ_padding = occ_padding;
    for (int i = 0; i < 3; ++i) p.occ_dims[size_t(i)] = int(od[size_t(i)]);
    finish_occupancy(p);
    return;
  }
#endif
  const size_t n = size_t(p.dims[0]) * p.dims[1] * p.dims[2];
  std::vector<float> density(n);
  for (size_t i = 0; i < n; ++i) density[i] = p.rgba[i * 4];
  occupancy_from(p, occ_cell, occ_padding, std::move(density));
  finish_occupancy(p);
}

}  // namespace cloudviewer
