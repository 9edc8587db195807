// Levels of detail: which level of a .vdb with density_level_N grids (cloudgen generate --lod) the
// viewer draws, from the screen size of a voxel (render.lod_bias) and the dense path's memory
// budget (render.dense_budget). No OpenGL, no file access: the caller gives the file's facts.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "cloudviewer/camera.h"
#include "cloudviewer/settings.h"

namespace cloudgen {
struct SceneInfo;
}

namespace cloudviewer {

/// What the choice needs to know of the file: level 0's active box (world metres, y up) and voxel
/// size, and how many coarser levels it holds. Level L has voxels 2^L times as large.
struct LodFile {
  glm::dvec3 box_min{0.0}, box_size{0.0};
  double voxel_size = 1;
  std::array<uint32_t, 3> dims{{0, 0, 0}};  ///< level 0's active box in voxels
  uint32_t levels = 0;                      ///< coarser levels: 1 .. levels
};

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
/// The choice's facts of a .vdb, from what cloudgen reads of its density grid's metadata.
LodFile lod_file_of(const cloudgen::SceneInfo& info);
#endif

struct LodPick {
  uint32_t level = 0;           ///< the level drawn (0 = full resolution)
  uint32_t by_screen = 0;       ///< the level the screen size alone asks for
  double voxel_pixels = 0;      ///< screen size of a level-0 voxel at the box's nearest point, pixels
  bool by_memory = false;       ///< a finer level was skipped because it exceeds the budget
  /// "level 2 of 3 (voxel 100 m): a level-0 voxel is 0.21 px at the nearest point, render.lod_bias 0"
  std::string describe(const LodFile& f, const RenderSettings& s) const;
};

/// Level L's active box in voxels: at most ceil(dims / 2^L) + 1 a side (the coarse voxels straddle
/// the fine box's faces).
std::array<uint32_t, 3> lod_dims(const std::array<uint32_t, 3>& dims, uint32_t level);

/// The coarsest level whose voxel still projects to at most 2^render.lod_bias pixels at the point of
/// the box nearest to the eye (so a positive bias draws coarser, a negative one finer), then coarser
/// while the level's dense texture and occupancy (prepared_bytes) exceed dense_budget_bytes(s)
/// under render.volume=auto or dense. A camera inside the box draws level 0 (bias aside).
LodPick choose_lod(const LodFile& f, const Camera& cam, int image_height, const RenderSettings& s);

}  // namespace cloudviewer
