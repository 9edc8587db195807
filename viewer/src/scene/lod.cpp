#include "cloudviewer/lod.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cloudviewer/memory_budget.h"
#include "cloudviewer/prepared_volume.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/view.h"
#endif

namespace cloudviewer {

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
LodFile lod_file_of(const cloudgen::SceneInfo& info) {
  LodFile f;
  f.box_min = glm::dvec3(info.origin[0], info.origin[1], info.origin[2]);
  f.box_size = glm::dvec3(info.size()[0], info.size()[1], info.size()[2]);
  f.voxel_size = info.voxel_size;
  f.dims = info.dims;
  f.levels = info.lod_levels;
  return f;
}
#endif

std::array<uint32_t, 3> lod_dims(const std::array<uint32_t, 3>& dims, uint32_t level) {
  std::array<uint32_t, 3> d{};
  for (int a = 0; a < 3; ++a)
    d[a] = level == 0 ? dims[a] : uint32_t((uint64_t(dims[a]) + (uint64_t(1) << level) - 1) >> level) + 1;
  return d;
}

LodPick choose_lod(const LodFile& f, const Camera& cam, int image_height, const RenderSettings& s) {
  LodPick p;
  if (f.levels == 0) return p;
  // Distance from the eye to the nearest point of the box (0 inside it).
  const glm::dvec3 lo = f.box_min, hi = f.box_min + f.box_size;
  const glm::dvec3 q = glm::clamp(cam.eye, lo, hi);
  const double dist = glm::length(cam.eye - q);
  // Pixels per metre at that distance on the image's vertical axis (a pinhole of fov_y_deg).
  const double focal_px = 0.5 * image_height / std::tan(glm::radians(std::clamp(cam.fov_y_deg, 1.0, 170.0)) * 0.5);
  p.voxel_pixels = dist > 0 ? f.voxel_size * focal_px / dist : INFINITY;
  // The coarsest level L with 2^L * voxel_pixels <= 2^bias pixels.
  const double want = std::isfinite(p.voxel_pixels) ? std::floor(s.lod_bias - std::log2(p.voxel_pixels)) : s.lod_bias;
  p.by_screen = uint32_t(std::clamp(want, 0.0, double(f.levels)));
  p.level = p.by_screen;
  if (s.volume != VolumeStorage::NanoVdb) {
    const uint64_t budget = dense_budget_bytes(s);
    while (p.level < f.levels) {
      const std::array<uint32_t, 3> d = lod_dims(f.dims, p.level);
      if (prepared_bytes(uint64_t(d[0]) * d[1] * d[2]) <= budget) break;
      ++p.level;
      p.by_memory = true;
    }
  }
  return p;
}

std::string LodPick::describe(const LodFile& f, const RenderSettings& s) const {
  std::ostringstream o;
  o.precision(3);
  o << "level of detail " << level << " of " << f.levels << " (voxel " << f.voxel_size * double(uint64_t(1) << level)
    << " m): a level-0 voxel is " << voxel_pixels << " px at the nearest point, render.lod_bias " << s.lod_bias;
  if (by_memory) o << "; level " << by_screen << " exceeds render.dense_budget, so coarser";
  return o.str();
}

}  // namespace cloudviewer
