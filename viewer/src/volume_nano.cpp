// The nanovdb volume path (render.volume=nanovdb, docs/nanovdb.md): the storage choice, and a
// PreparedVolume that holds NanoVDB grids instead of the dense RGBA copy.
#include <cmath>
#include <string>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
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
  return prepared_bytes(voxels) > dense_budget_bytes(s);
}

uint64_t volume_gpu_bytes(const PreparedVolume& v) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (v.nano) {
    // The grids, the occupancy and the GL renderer's leaf page table (8 bytes per 8^3 leaf cell).
    uint64_t cells = 1;
    for (int a = 0; a < 3; ++a) {
      const int64_t lo = v.nano->index_min[size_t(a)] & ~7, hi = int64_t(v.nano->index_min[size_t(a)]) + v.dims[size_t(a)] - 1;
      cells *= uint64_t((hi - lo) / 8 + 1);
    }
    return v.nano->bytes() + v.occ.size() + cells * 8;
  }
#endif
  return uint64_t(v.rgba.size()) * sizeof(float) + v.occ.size();
}

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
  p.voxel_size = n->voxel_size;
  p.origin = glm::dvec3(n->origin[0], n->origin[1], n->origin[2]);
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
