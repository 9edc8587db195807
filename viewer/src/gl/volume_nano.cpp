// The nanovdb volume path (render.volume=nanovdb, docs/nanovdb.md): the storage choice, and a
// PreparedVolume that holds NanoVDB grids instead of the dense RGBA copy.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/motion.h"
#include "cloudgen/nvdb.h"
#endif

namespace cloudviewer {

uint64_t dense_budget_bytes(const RenderSettings& s) {
  // The default: a third of the free memory. While a dense volume loads, the reader's channels,
  // the RGBA copy and the GL texture (system memory on llvmpipe) are all held at once.
  return s.dense_budget > 0 ? uint64_t(s.dense_budget * 1048576.0) : available_memory_bytes() / 3;
}

bool use_nanovdb(const RenderSettings& s, uint64_t voxels) {
  switch (s.volume) {
    case VolumeStorage::Dense: return false;
    case VolumeStorage::NanoVdb: return true;
    case VolumeStorage::Auto: break;
  }
  // Also beyond 2 GiB of RGBA32F texture, which llvmpipe (and other drivers) cannot allocate as one
  // texture whatever the budget: cumulus-field at 1024 failed there with "out of GPU memory".
  return prepared_bytes(voxels) > dense_budget_bytes(s) || voxels * 16 >= kDenseTextureLimit;
}

uint64_t nano_grid_bytes(const PreparedVolume& v) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (v.nano) return v.nano->bytes();
#endif
  (void)v;
  return 0;
}

uint64_t volume_gpu_bytes(const PreparedVolume& v, NanoLookup lookup) {
  const uint64_t skipping = v.occ.size() * 2;  // the R8 occupancy and R8UI distance textures
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (v.nano) {
    // The brick atlas (GL) leaves the grids and the page table on the CPU; its own size is known
    // once it is built (the renderer prints it).
    if (lookup == NanoLookup::Atlas) return skipping;
    // The grids and the GL renderer's leaf page table (8 bytes per 8^3 leaf cell).
    uint64_t cells = 1;
    for (int a = 0; a < 3; ++a) {
      const int64_t lo = v.nano->index_min[size_t(a)] & ~7, hi = int64_t(v.nano->index_min[size_t(a)]) + v.dims[size_t(a)] - 1;
      cells *= uint64_t((hi - lo) / 8 + 1);
    }
    // (uploaded for the accessor too, when every grid has one: one upload serves both lookups)
    const bool table = !v.has_detail || v.nano->detail_shared_layout;
    return v.nano->bytes() + skipping + (table ? cells * 8 : 0);
  }
#endif
  (void)lookup;
  return uint64_t(v.rgba.size()) * sizeof(float) + skipping;
}

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
NanoAtlas build_nano_atlas(const PreparedVolume& v, int max_side, uint64_t max_bytes) {
  NanoAtlas a;
  if (!v.nano) return a;
  const cloudgen::NanoVolume& n = *v.nano;
  const int channels = v.has_detail ? 4 : 1;
  // Each grid's leaf page table: a voxel's value is one word of the buffer (docs in nvdb.h).
  std::vector<cloudgen::NanoPages> pages;
  pages.push_back(cloudgen::nano_pages(n, 0));
  if (v.has_detail)
    for (int g = 0; g < 3; ++g) pages.push_back(cloudgen::nano_pages(n, size_t(n.detail[size_t(g)])));
  auto word = [data = n.data()](uint32_t w) {  // the float at word index w of the grids' buffer
    float f;
    std::memcpy(&f, data + size_t(w) * 4, 4);
    return f;
  };
  auto value = [&](size_t g, std::array<int32_t, 3> ijk) {
    const cloudgen::NanoPages& t = pages[g];
    size_t i = 0, stride = 1;
    for (int k = 0; k < 3; ++k) {
      const int32_t c = (ijk[size_t(k)] - t.origin[size_t(k)]) >> 3;
      if (c < 0 || c >= int32_t(t.dims[size_t(k)])) return 0.0f;
      i += size_t(c) * stride;
      stride *= t.dims[size_t(k)];
    }
    const uint32_t e = t.entries[i];
    if (e & cloudgen::NanoPages::kNanoConstant) return word(e & ~cloudgen::NanoPages::kNanoConstant);
    return word(e + uint32_t((ijk[0] & 7) << 6 | (ijk[1] & 7) << 3 | (ijk[2] & 7)));
  };
  const int B = NanoAtlas::kBrick;
  for (int k = 0; k < 3; ++k) a.cells[size_t(k)] = v.dims[size_t(k)] / 8 + 1;
  const size_t ncell = size_t(a.cells[0]) * a.cells[1] * a.cells[2];
  a.index.assign(ncell * 4, 0);
  // The bricks in cell order, then laid into the texture.
  std::vector<float> bricks, brick(size_t(B * B * B) * channels);
  std::vector<uint32_t> number(ncell, 0);  // brick number + 1 (0: none)
  auto texel = [&](int t, int k) {  // the dense sampler's clamp (y, or x/z of a non-tiling volume) or wrap
    const int d = v.dims[size_t(k)];
    if (v.tiles && k != 1) return ((t % d) + d) % d;
    return std::clamp(t, 0, d - 1);
  };
  // A cell can hold density only where a density leaf cell it reads is not a constant 0 (a tile
  // or the background): checked first, so the scan costs the occupied leaves, not the box, and
  // an atlas over the budget is refused before its bricks are read.
  const cloudgen::NanoPages& dp = pages[0];
  auto may_hold = [&](int cx, int cy, int cz) {
    std::array<std::array<int32_t, 9>, 3> leaf;  // the distinct leaf cells of the 9 texels per axis (a wrap: up to 4)
    std::array<int, 3> count{{0, 0, 0}};
    const int c3[3] = {cx, cy, cz};
    for (int k = 0; k < 3; ++k)
      for (int x = 0; x < B; ++x) {
        const int32_t l = (texel(8 * c3[k] - 1 + x, k) + n.index_min[size_t(k)] - dp.origin[size_t(k)]) >> 3;
        bool seen = false;
        for (int j = 0; j < count[size_t(k)]; ++j) seen = seen || leaf[size_t(k)][size_t(j)] == l;
        if (!seen) leaf[size_t(k)][size_t(count[size_t(k)]++)] = l;
      }
    for (int i = 0; i < count[0]; ++i)
      for (int j = 0; j < count[1]; ++j)
        for (int k = 0; k < count[2]; ++k) {
          const int32_t l[3] = {leaf[0][size_t(i)], leaf[1][size_t(j)], leaf[2][size_t(k)]};
          bool inside = true;
          for (int q = 0; q < 3; ++q) inside = inside && l[q] >= 0 && l[q] < int32_t(dp.dims[size_t(q)]);
          if (!inside) continue;
          const uint32_t e = dp.entries[(size_t(l[2]) * dp.dims[1] + l[1]) * dp.dims[0] + l[0]];
          if (!(e & cloudgen::NanoPages::kNanoConstant) || word(e & ~cloudgen::NanoPages::kNanoConstant) > 0.0f) return true;
        }
    return false;
  };
  std::vector<uint8_t> maybe(ncell, 0);
  size_t bound = 0;
  for (int cz = 0; cz < a.cells[2]; ++cz)
    for (int cy = 0; cy < a.cells[1]; ++cy)
      for (int cx = 0; cx < a.cells[0]; ++cx)
        if (may_hold(cx, cy, cz)) maybe[(size_t(cz) * a.cells[1] + cy) * a.cells[0] + cx] = 1, ++bound;
  if (uint64_t(bound) * brick.size() * 4 + a.index.size() * 2 > max_bytes) return NanoAtlas{};
  for (int cz = 0; cz < a.cells[2]; ++cz)
    for (int cy = 0; cy < a.cells[1]; ++cy)
      for (int cx = 0; cx < a.cells[0]; ++cx) {
        const size_t cell = (size_t(cz) * a.cells[1] + cy) * a.cells[0] + cx;
        if (!maybe[cell]) continue;
        bool any = false;
        for (int z = 0; z < B; ++z)
          for (int y = 0; y < B; ++y)
            for (int x = 0; x < B; ++x) {
              const std::array<int32_t, 3> ijk = {texel(8 * cx - 1 + x, 0) + n.index_min[0],
                                                  texel(8 * cy - 1 + y, 1) + n.index_min[1],
                                                  texel(8 * cz - 1 + z, 2) + n.index_min[2]};
              float* out = &brick[((size_t(z) * B + y) * B + x) * channels];
              out[0] = std::max(value(0, ijk), 0.0f);  // as prepare_volume clamps the dense copy
              any = any || out[0] > 0.0f;
              for (int c = 1; c < channels; ++c) out[c] = value(size_t(c), ijk);
            }
        if (!any) continue;
        number[cell] = uint32_t(1 + a.bricks);
        bricks.insert(bricks.end(), brick.begin(), brick.end());
        ++a.bricks;
      }
  a.channels = channels;
  const int per_side = std::max(1, max_side / B);
  const size_t nb = std::max<size_t>(a.bricks, 1);
  a.layout[0] = int(std::min<size_t>(nb, size_t(per_side)));
  a.layout[1] = int(std::min<size_t>((nb + a.layout[0] - 1) / a.layout[0], size_t(per_side)));
  const size_t plane = size_t(a.layout[0]) * a.layout[1];
  a.layout[2] = int((nb + plane - 1) / plane);
  const uint64_t texels = uint64_t(a.layout[0]) * a.layout[1] * a.layout[2] * B * B * B;
  if (a.layout[2] > per_side || texels * channels * 4 + a.index.size() * 2 > max_bytes) return NanoAtlas{};
  const size_t W = size_t(a.layout[0]) * B, H = size_t(a.layout[1]) * B;
  a.texels.assign(size_t(texels) * channels, 0.0f);
  for (size_t cell = 0; cell < ncell; ++cell) {
    if (number[cell] == 0) continue;
    uint16_t* e = &a.index[cell * 4];
    const size_t b = size_t(number[cell]) - 1;
    const size_t bx = b % a.layout[0], by = (b / a.layout[0]) % a.layout[1], bz = b / plane;
    e[0] = uint16_t(bx * B), e[1] = uint16_t(by * B), e[2] = uint16_t(bz * B), e[3] = 1;
    const float* src = &bricks[b * brick.size()];
    for (int z = 0; z < B; ++z)
      for (int y = 0; y < B; ++y)
        std::memcpy(&a.texels[(((bz * B + z) * H + by * B + y) * W + bx * B) * channels],
                    src + ((size_t(z) * B + y) * B) * channels, sizeof(float) * B * channels);
  }
  return a;
}
#else
NanoAtlas build_nano_atlas(const PreparedVolume&, int, uint64_t) { return NanoAtlas{}; }
#endif

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
PreparedVolume prepare_nano(std::shared_ptr<const cloudgen::NanoVolume> n, int occ_cell, int occ_padding) {
  PreparedVolume p;
  for (int i = 0; i < 3; ++i) {
    if (n->dims[size_t(i)] == 0) throw InputError("volume has no density (not a cloud volume)");
    p.dims[size_t(i)] = int(n->dims[size_t(i)]);
  }
  // PNanoVDB's GLSL mode addresses the buffer with 32-bit byte offsets.
  if (n->bytes() >= (uint64_t(1) << 32))
    throw InputError("NanoVDB grids of " + std::to_string(n->bytes() >> 20) +
                     " MiB: the shader addresses at most 4 GiB (export at a lower resolution)");
  if (!(n->voxel_size > 0) || !std::isfinite(n->voxel_size) || n->voxel_size > 1e5)
    throw InputError("volume voxel size " + std::to_string(n->voxel_size) + " m: must be a finite number in (0, 1e5] metres");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(n->origin[size_t(i)]) || std::abs(n->origin[size_t(i)]) > 1e8)
      throw InputError("volume origin " + std::to_string(n->origin[size_t(i)]) + " m: must be finite, |x| <= 1e8 m");
  // The memory estimate counts the voxels of active tiles: each is sampled and lit like a leaf's
  // voxel (the atlas stores it as one), but holds no bytes in the file or the grids. A 17 KB .vdb
  // of one active 65536^3 region, estimated by its few thousand tiles, kept the CPU viewer busy
  // for minutes (issue 47); such a file is refused here, before any occupancy or light cache is
  // built. The leaves' voxels are already in memory (the grids' buffer), so only the tiles' count:
  // every grid's active voxels beyond what its leaves can hold, 4 bytes each.
  uint64_t tile_voxels = 0;
  for (const cloudgen::NanoVolume::Grid& g : n->grids) {
    const uint64_t in_leaves = uint64_t(g.leaves) * 512;
    const uint64_t beyond = g.active_voxels > in_leaves ? g.active_voxels - in_leaves : 0;
    tile_voxels = tile_voxels > UINT64_MAX - beyond ? UINT64_MAX : tile_voxels + beyond;
  }
  const uint64_t tile_bytes = tile_voxels > UINT64_MAX / 4 ? UINT64_MAX : tile_voxels * 4;
  if (tile_bytes > available_memory_bytes()) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "its active tiles cover %llu voxels, which need about %.1f GiB of memory to render as "
                  "voxels; %.1f GiB is available",
                  static_cast<unsigned long long>(tile_voxels), double(tile_bytes) / double(1u << 30),
                  double(available_memory_bytes()) / double(1u << 30));
    throw InputError(std::string("volume (NanoVDB grids): ") + text +
                     " (a damaged file, or one region marked active as a whole: store the clouds' voxels instead)");
  }
  p.voxel_size = n->voxel_size;
  p.origin = glm::dvec3(n->origin[0], n->origin[1], n->origin[2]);
  // The height range the clouds' height fraction spans (ambient light, motion), as prepare_volume:
  // the box, or the generator's whole layer when the file records it.
  p.height_min = p.origin.y;
  p.height_size = double(p.dims[1]) * p.voxel_size;
  double box_min = 0, box_height = 0;
  if (cloudgen::motion_height_box(n->metadata, box_min, box_height)) p.height_min = box_min, p.height_size = box_height;
  for (const auto& kv : n->metadata) p.baked_motion |= kv.first == "time_seconds";
  p.tiles = n->tiles_xz;
  p.has_detail = n->has_detail();
  p.nano = std::move(n);
  build_occupancy(p, occ_cell, occ_padding);
  return p;
}
#else
PreparedVolume prepare_nano(std::shared_ptr<const cloudgen::NanoVolume>, int, int) {
  throw InputError("render.volume=nanovdb: this cloudviewer was built without the cloudgen library");
}
#endif

}  // namespace cloudviewer
