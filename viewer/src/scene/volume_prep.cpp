// Densifying: a cloudgen::Volume into the interleaved RGBA floats and the occupancy grid both
// renderers sample, with the memory it needs estimated first.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"
#include "cloudgen/erosion.h"

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

// The occupancy grid of `density` (p.dims, x fastest) through cloudgen's one builder.
void occupancy_from(PreparedVolume& p, int occ_cell, int occ_padding, const float* density) {
  const std::array<uint32_t, 3> dims{uint32_t(p.dims[0]), uint32_t(p.dims[1]), uint32_t(p.dims[2])};
  std::array<uint32_t, 3> od{};
  p.occ = cloudgen::occupancy_cells(density, dims, uint32_t(occ_cell), uint32_t(occ_padding), p.tiles, od);
  p.occ_cell = occ_cell;
  p.occ_padding = occ_padding;
  for (int i = 0; i < 3; ++i) p.occ_dims[size_t(i)] = int(od[size_t(i)]);
}

void finish_occupancy(PreparedVolume& p) {
  size_t count = 0;
  for (uint8_t o : p.occ) count += o ? 1 : 0;
  p.occupied_fraction = p.occ.empty() ? 0 : double(count) / double(p.occ.size());
  build_distance_field(p, p.dist_rule);
}

// Filtered lookups land within a rounding of the convex combination erosion_bound bounds: a texel
// counts as holding density unless its bound is below minus this (relative to 1 + its base).
constexpr double kErosionBoundMargin = 1e-4;

// The moved grid keeps cells of about this many voxels whatever render.occupancy_cell is: finer
// static cells serve the still frame's distance jumps, but a moved grid as fine would make each
// moving frame's large steps half (a quarter) as long and its per-frame build 8 (64) times the cells.
constexpr int kMovedCellVoxels = 8;

}  // namespace

bool field_covers(const FieldRule& built, const FieldRule& needed) {
  if (built.erosion <= 0) return true;  // the base alone: whatever erodes, moves or is placed
  return needed.erosion >= built.erosion && needed.layer == built.layer && needed.height_slack <= built.height_slack;
}

void build_distance_field(PreparedVolume& p, FieldRule rule) {  // by value: callers pass p.dist_rule
  // The distance field counts cells to the nearest cell that holds density (the grid before its
  // padding): the empty radius (lighting.glsl) accounts for trilinear reach itself, so the padding,
  // which only the thesis's one-cell step needs, would shorten every jump by its width.
  const int c = p.occ_cell;
  std::vector<uint8_t> holds(p.occ.size(), 0);
  p.dist_rule = FieldRule{};
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (p.nano) {  // no dense copy: the cells holding active voxels (a superset of density > 0), unpadded
    std::array<uint32_t, 3> od{};
    holds = cloudgen::nano_occupancy(*p.nano, uint32_t(c), 0, od);
    if (holds.size() != p.occ.size()) holds.assign(p.occ.size(), 1);
    p.dist = occupancy_distance(holds, p.occ_dims, p.tiles, p.dims, p.occ_cell);
    p.moved_near_sat = moved_near_table(p, moved_reach_cells(p));
    return;
  }
#endif
  const bool eroded = rule.erosion > 0 && p.has_detail;
  if (eroded) p.dist_rule = rule;
  // One slab of cells (c voxel planes in z) per task: no two tasks write the same cell.
  tbb::parallel_for(tbb::blocked_range<int>(0, p.occ_dims[2]), [&](const tbb::blocked_range<int>& slabs) {
    for (int z = slabs.begin() * c; z < std::min(p.dims[2], slabs.end() * c); ++z)
      for (int y = 0; y < p.dims[1]; ++y) {
        // The heights the texels of this row are seen at: their trilinear reach (a voxel either side
        // of the centre), in the layer's or the box's height fractions, widened by the slack.
        double h0 = 0, h1 = 0;
        if (eroded) {
          if (rule.layer) {
            h0 = (y - 0.5) / p.dims[1], h1 = (y + 1.5) / p.dims[1];
          } else {
            h0 = (p.origin.y + (y - 0.5) * p.voxel_size - p.height_min) / p.height_size;
            h1 = (p.origin.y + (y + 1.5) * p.voxel_size - p.height_min) / p.height_size;
          }
          h0 -= rule.height_slack, h1 += rule.height_slack;
        }
        const float* row = &p.rgba[((size_t(z) * p.dims[1] + y) * p.dims[0]) * 4];
        uint8_t* cells = &holds[(size_t(z / c) * p.occ_dims[1] + y / c) * p.occ_dims[0]];
        for (int x = 0; x < p.dims[0]; ++x) {
          const float* t = row + size_t(x) * 4;
          const double base = t[0];
          if (!(base > 0)) continue;
          if (eroded) {
            namespace eg = cloudgen::erosion_glsl;
            const double bound = eg::erosion_bound(base, eg::erosion_detail(t[1], t[2], t[3]), h0, h1, rule.erosion);
            if (bound < -kErosionBoundMargin * (1.0 + base)) continue;
          }
          cells[x / c] = 1;
        }
      }
  });
  p.dist = occupancy_distance(holds, p.occ_dims, p.tiles, p.dims, p.occ_cell);
  p.moved_near_sat = moved_near_table(p, moved_reach_cells(p));
}

int moved_reach_cells(const PreparedVolume& vol) {
  if (vol.dist.empty() || vol.dist.size() != vol.occ.size() || vol.occ_cell <= 0) return 1;
  return std::max(1, kMovedCellVoxels / vol.occ_cell);
}

std::vector<uint32_t> moved_near_table(const PreparedVolume& vol, int reach, bool use_dist) {
  use_dist = use_dist && vol.dist.size() == vol.occ.size();
  const int sx = vol.occ_dims[0], sy = vol.occ_dims[1], sz = vol.occ_dims[2];
  if (vol.occ.size() != size_t(sx) * sy * sz) return {};
  std::vector<uint32_t> sat(size_t(sy) * (sz + 1) * (sx + 1), 0);
  auto at = [&](int y, int z, int x) -> uint32_t& { return sat[(size_t(y) * (sz + 1) + z) * (sx + 1) + x]; };
  for (int y = 0; y < sy; ++y)
    for (int z = 0; z < sz; ++z)
      for (int x = 0; x < sx; ++x) {
        const size_t i = (size_t(z) * sy + y) * sx + x;
        const uint32_t near = use_dist ? vol.dist[i] <= reach : vol.occ[i] != 0;
        at(y, z + 1, x + 1) = near + at(y, z, x + 1) + at(y, z + 1, x) - at(y, z, x);
      }
  return sat;
}

namespace {

/// h(i) = min_j max(|i - j|, g(j)) over one line of n values, in time linear in n. Forward,
/// F(i) = min over j <= i: a candidate j is dominated for good by a later k with g(k) <= g(j)
/// (nearer, no higher), so the kept ones (`dq`, a deque of indices) have increasing g; the front
/// j is the best while i - j < g(second) (its term, below g(second), is below every later term),
/// and is dominated for good once i - j reaches it. Backward likewise; h is the smaller.
void linf_sweep(const int* g, int* h, int n, int* dq) {
  for (int pass = 0; pass < 2; ++pass) {
    int head = 0, tail = 0;
    for (int s = 0; s < n; ++s) {
      const int i = pass == 0 ? s : n - 1 - s;
      while (tail > head && g[dq[tail - 1]] >= g[i]) --tail;
      dq[tail++] = i;
      while (tail - head >= 2 && std::abs(i - dq[head]) >= g[dq[head + 1]]) ++head;
      const int v = std::max(std::abs(i - dq[head]), g[dq[head]]);
      h[i] = pass == 0 ? v : std::min(h[i], v);
    }
  }
}

}  // namespace

std::vector<uint8_t> occupancy_distance(const std::vector<uint8_t>& occ, const std::array<int, 3>& n, bool tiles,
                                        const std::array<int, 3>& dims, int cell) {
  const size_t count = size_t(n[0]) * n[1] * n[2];
  std::vector<uint8_t> out(count, 0);
  if (count == 0 || occ.size() != count) return out;
  // Wrapping across x/z is exact in cells only when the tile is a whole number of cells. Otherwise
  // the last cell is partial (narrower than a cell, at least a voxel), so a route across the seam
  // is up to one cell shorter than its count of cells: such a tile takes the smaller of the field
  // without wrapping (exact for routes that do not cross) and the wrapped field less one (a lower
  // bound for routes that do; L-infinity loses at most one cell however many axes it crosses).
  const bool exact_wrap = tiles && dims[0] % cell == 0 && dims[2] % cell == 0;
  const bool partial_wrap = tiles && !exact_wrap;
  // The L-infinity (chessboard) distance to the nearest occupied cell, d(p) = min_q max_i |p_i - q_i|,
  // is separable because max distributes over min: one pass per axis of
  //     h(i) = min_j max(|i - j|, g(j))
  // along every line (g: the previous pass's values; the first pass's g is 0 on occupied cells and
  // "none" elsewhere). The lines are independent (all cores), and each is linear in its length
  // (linf_sweep). A wrapping axis is swept over the line with half of it copied on either side,
  // which holds every route around the seam (none is longer than half the line). (A breadth-first search over the 26 neighbours
  // gave the same field in 85 ms of one core for the 2 M cells of a 256^3 volume.)
  const int inf = 1 << 20;
  auto transform = [&](bool wrap) {
    std::vector<int> f(count);
    for (size_t i = 0; i < count; ++i) f[i] = occ[i] ? 0 : inf;
    for (int axis = 0; axis < 3; ++axis) {
      const int len = n[size_t(axis)];
      const bool wraps = wrap && axis != 1;
      const size_t stride = axis == 0 ? 1 : axis == 1 ? size_t(n[0]) : size_t(n[0]) * n[1];
      // A wrapping line is swept with half a line before and after it: a route around the seam
      // is never longer than half the line.
      const int before = wraps ? len / 2 + 1 : 0, total = len + 2 * before;
      // Lines along y and z are strided in memory: kWide neighbouring lines (adjacent in x, so
      // their cells are adjacent) move together through a tile, a cache line per row at a time.
      constexpr size_t kWide = 16;
      const size_t width = axis == 0 ? 1 : kWide, inner = axis == 0 ? 1 : stride;
      const size_t per_outer = (inner + width - 1) / width, outer = count / (size_t(len) * inner);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, outer * per_outer, axis == 0 ? 64 : 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<int> tile(static_cast<size_t>(total) * width), g(static_cast<size_t>(total)), h(g.size()), deque(g.size());
        for (size_t b = r.begin(); b != r.end(); ++b) {
          const size_t o = b / per_outer, s0 = (b % per_outer) * width, w = std::min(width, inner - s0);
          const size_t base = o * inner * size_t(len) + s0;  // the first cell of the block's first line
          const size_t step = axis == 0 ? 1 : stride;
          for (int k = 0, i = (len - before % len) % len; k < total; ++k, i = i + 1 == len ? 0 : i + 1)
            std::copy_n(&f[base + size_t(i) * step], w, &tile[size_t(k) * width]);  // i = (k - before) mod len
          for (size_t c = 0; c < w; ++c) {
            bool any = false;
            for (int k = 0; k < total; ++k) {
              g[size_t(k)] = tile[size_t(k) * width + c];
              any = any || g[size_t(k)] < inf;
            }
            if (!any) continue;  // nothing along this line yet: it stays "none"
            linf_sweep(g.data(), h.data(), total, deque.data());
            for (int i = 0; i < len; ++i) tile[size_t(before + i) * width + c] = std::min(h[size_t(before + i)], inf);
          }
          for (int i = 0; i < len; ++i) std::copy_n(&tile[size_t(before + i) * width], w, &f[base + size_t(i) * step]);
        }
      });
    }
    return f;
  };
  std::vector<int> f = transform(exact_wrap);
  if (partial_wrap) {
    const std::vector<int> wrapped = transform(true);
    for (size_t i = 0; i < count; ++i)
      if (!occ[i]) f[i] = std::max(1, std::min(f[i], wrapped[i] - 1));  // 0 stays "holds density"
  }
  for (size_t i = 0; i < count; ++i) out[i] = uint8_t(std::min(f[i], 255));
  return out;
}

int occupancy_cell_for(int cell, uint64_t nx, uint64_t ny, uint64_t nz) {
  auto cells = [&](uint64_t c) { return ((nx + c - 1) / c) * ((ny + c - 1) / c) * ((nz + c - 1) / c); };
  uint64_t c = uint64_t(std::max(cell, 1));
  while (c < 4 && cells(c) > kMaxFineOccupancyCells) c *= 2;
  while (c < 1024 && cells(c) > kMaxOccupancyCells) c *= 2;
  return int(c);
}

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

PreparedVolume prepare_volume(const cloudgen::Volume& v, int occ_cell, int occ_padding, const RenderSettings* fit,
                              std::vector<float>* spare) {
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
  p.height_min = p.origin.y;
  p.height_size = double(v.dims[1]) * v.voxel_size;
  double box_min = 0, box_height = 0;
  if (cloudgen::motion_height_box(v.metadata, box_min, box_height)) p.height_min = box_min, p.height_size = box_height;
  for (const auto& kv : v.metadata) p.baked_motion |= kv.first == "time_seconds";
  p.tiles = v.tiles_xz;
  p.has_detail = true;
  for (int c = 0; c < 3; ++c) {
    if (!v.detail[size_t(c)].empty() && v.detail[size_t(c)].size() != n)
      throw InputError("volume detail channel " + std::to_string(c) + " has the wrong size");
    if (v.detail[size_t(c)].empty()) p.has_detail = false;
  }
  if (spare) p.rgba = std::move(*spare), *spare = {};  // no fresh pages to fault in; every value is written below
  p.rgba.resize(n * 4);
  // Interleaved on all cores (an edit's regeneration waits for it: about 0.2 s for 256^3 on one);
  // the first non-finite voxel is found again in order, so the message does not depend on them.
  std::atomic<bool> nonfinite{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, size_t(1) << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const float d = v.density[i];
      if (!std::isfinite(d)) nonfinite = true;
      p.rgba[i * 4] = std::max(d, 0.f);
      for (int c = 0; c < 3; ++c) p.rgba[i * 4 + 1 + size_t(c)] = v.detail[size_t(c)].empty() ? 0.f : v.detail[size_t(c)][i];
    }
  });
  if (nonfinite)
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(v.density[i]))
        throw InputError("volume density has a non-finite value at voxel " + std::to_string(i));
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
  } else {  // from the volume's own density (density > 0 is p.rgba's max(d, 0) > 0): no copy
    occupancy_from(p, occ_cell, occ_padding, v.density.data());
  }
  if (fit) p.dist_rule = field_rule(p, *fit);  // one build of the field, the one the settings need
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
  occupancy_from(p, occ_cell, occ_padding, density.data());
  finish_occupancy(p);
}

}  // namespace cloudviewer
