// A volume in the form both renderers sample: interleaved RGBA floats, the occupancy grid and its
// distance field. src/scene/volume_prep.cpp (dense), src/gl/volume_nano.cpp (NanoVDB).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cloudgen/volume.h"
#include "cloudviewer/settings.h"

namespace cloudgen {
struct NanoVolume;  // cloudgen/nvdb.h
}

namespace cloudviewer {

/// What the distance field's cells assume about the density (docs/viewer-speed.md, "The eroded
/// field"). With erosion 0 a cell holds density when one of its voxels has base density > 0, which
/// holds for every setting. With erosion E > 0 only when a voxel's base can exceed the erosion
/// threshold its detail gives at strength E (cloudgen/erosion.glsl erosion_bound) at a height it
/// can be seen at: its trilinear reach, widened by `height_slack` (height fractions) for the
/// motion's up flow. A field built so serves frames that erode at least as much, with no more up
/// flow, in the same placement (field_covers).
struct FieldRule {
  double erosion = 0;       ///< the erosion strength the field assumed (0: the base alone)
  double height_slack = 0;  ///< how far (height fractions) the seen height may lie from the texel's
  bool layer = false;       ///< heights are the layer's (texture v), not the box's height_min/size
  bool operator==(const FieldRule& o) const {
    return erosion == o.erosion && height_slack == o.height_slack && layer == o.layer;
  }
  bool operator<(const FieldRule& o) const {
    if (erosion != o.erosion) return erosion < o.erosion;
    if (height_slack != o.height_slack) return height_slack < o.height_slack;
    return layer < o.layer;
  }
};
/// Whether a field built for `built` is exact for a frame that needs `needed` (field_rule).
bool field_covers(const FieldRule& built, const FieldRule& needed);

/// Volume in the form both renderers sample: interleaved RGBA floats and the occupancy grid.
struct PreparedVolume {
  std::array<int, 3> dims{{0, 0, 0}};
  double voxel_size = 1;
  glm::dvec3 origin{0.0};
  bool tiles = false;
  bool has_detail = false;
  std::vector<float> rgba;  ///< x fastest, 4 channels
  int occ_cell = 8;         ///< voxels per coarse cell
  int occ_padding = 2;      ///< dilation in coarse cells
  std::array<int, 3> occ_dims{{0, 0, 0}};
  std::vector<uint8_t> occ;
  /// Distance field of the coarse grid: per cell, the L-infinity distance in cells to the nearest
  /// cell holding a voxel with density > 0 (the grid before padding; 0 there, capped at 255); see
  /// occupancy_distance. Distance skipping proves density 0 within (d - 1) cells - half a voxel.
  std::vector<uint8_t> dist;
  /// What `dist` (and moved_near_sat) assumed: the base alone unless fit_distance_field eroded it.
  FieldRule dist_rule;
  /// Moving clouds (box mode) skip through a grid make_frame builds every frame over the march box
  /// (frame.cpp build_moved_occupancy), whose cells are moved_reach_cells(*this) static cells wide
  /// and marked where a static cell they can show lies within that many cells of density. Built
  /// with the grid (moved_near_table): per static y layer, a summed-area table over (x, z) of those
  /// cells, (occ_dims.z + 1) x (occ_dims.x + 1) entries per layer, so no frame rebuilds it.
  std::vector<uint32_t> moved_near_sat;
  double occupied_fraction = 0;
  /// The box the motion measures heights in (y, world metres): the whole preset's when the file
  /// records it (cloudgen's motion.box_min_y / motion.box_height), else this volume's own.
  double height_min = 0, height_size = 1;
  /// A frame of a baked motion sequence (its metadata has time_seconds): already displaced, so the
  /// viewer shows it still.
  bool baked_motion = false;
  /// render.volume=nanovdb: the NanoVDB grids both renderers march (rgba is then empty).
  std::shared_ptr<const cloudgen::NanoVolume> nano;
  glm::dvec3 size() const { return glm::dvec3(dims[0], dims[1], dims[2]) * voxel_size; }
  glm::dvec3 center() const { return origin + 0.5 * size(); }
};

/// Validates the volume (size, memory, non-empty density, finite values) and takes its occupancy
/// grid: the volume's own when it carries one for this cell and padding (cloudgen builds it with
/// cloudgen::build_occupancy), else built with that same function. A cell is occupied when a voxel
/// within `padding` cells (26-neighbourhood, wrapped in x/z when tiling) has density > 0; that
/// conservativeness is what makes skipping image-neutral (trilinear reads reach half a voxel into
/// the next cell).
/// With `fit`, the distance field is built once for the rule those settings need (field_rule), as
/// fit_distance_field would rebuild it; without, for the base alone.
/// `spare`: memory to put the interleaved channels in (a volume no longer drawn; its values are
/// all overwritten), taken when given.
PreparedVolume prepare_volume(const cloudgen::Volume& v, int occ_cell, int occ_padding = 2,
                              const RenderSettings* fit = nullptr, std::vector<float>* spare = nullptr);
/// Rebuilds only the occupancy grid with another cell size / padding (cloudgen::build_occupancy).
void build_occupancy(PreparedVolume& p, int occ_cell, int occ_padding);
/// The most coarse cells render.occupancy_cell gets below 4 voxels: 2^23 (8 M). Opening a volume and
/// refitting its distance field (the panel's erosion) take about 150 ns a cell: cumulus-field 1024
/// opened in 4.0 s at 2-voxel cells (19 M), 1.0 s at 4.
constexpr uint64_t kMaxFineOccupancyCells = uint64_t(1) << 23;
/// The most coarse cells at any size: 2^25 (32 M; the grid and its distance field a byte each, the
/// field's search 8 bytes a cell while it runs).
constexpr uint64_t kMaxOccupancyCells = uint64_t(1) << 25;
/// render.occupancy_cell for a volume of nx x ny x nz voxels: `cell`, doubled while it is under 4
/// voxels and the grid has more than kMaxFineOccupancyCells cells, then while it has more than
/// kMaxOccupancyCells (the default 2 stays 2 on the thesis volume and cumulus-field 512 and
/// becomes 4 on cumulus-field 1024 and 2048).
int occupancy_cell_for(int cell, uint64_t nx, uint64_t ny, uint64_t nz);

/// Bytes prepare_volume allocates for a volume of `voxels` voxels (RGBA floats, occupancy).
uint64_t prepared_bytes(uint64_t voxels);
/// The nanovdb path (render.volume=nanovdb): the volume fields, has_detail and the occupancy grid
/// from the NanoVDB density grid's leaves and tiles (cloudgen::nano_occupancy: the same cells as
/// the dense builder, no dense copy). Validates like prepare_volume. Needs cloudgen.
PreparedVolume prepare_nano(std::shared_ptr<const cloudgen::NanoVolume> n, int occ_cell, int occ_padding = 2);

}  // namespace cloudviewer
