// Empty-space skipping's distance field over the occupancy grid: built, fitted to the frame's
// erosion and motion, and its moved-cloud tables. Exact, so skipping never changes the image.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudviewer {

/// Rebuilds the distance field (and moved_near_sat) under `rule` from the dense texels; a NanoVDB
/// volume keeps the base rule (its cells come from the active voxels).
void build_distance_field(PreparedVolume& p, FieldRule rule);
/// The rule the frame of settings `s` needs: its erosion when it erodes (the volume has detail,
/// erosion > 0) and no curl distortion moves the detail away from the base, the motion's up flow
/// as height slack, the placement.
FieldRule field_rule(const PreparedVolume& vol, const RenderSettings& s);
/// Rebuilds the distance field for `s` when its rule does not cover field_rule(vol, s); true when
/// it did (the renderer then needs set_distance_field). make_frame never trusts a field that does not
/// cover its settings: it skips by the thesis scheme instead.
bool fit_distance_field(PreparedVolume& vol, const RenderSettings& s);

/// The distance field of an occupancy grid of `n` cells (x fastest): for each cell, the L-infinity
/// (Chebyshev) distance in cells to the nearest occupied cell, exact, 0 on occupied cells, capped at
/// 255 (also when the grid has none). Wrapped in x and z when `tiles` and the `dims` are whole
/// multiples of `cell`; a tiling volume whose cells do not divide it has a partial last cell, so
/// there the field is the smaller of the unwrapped field and the wrapped one less one, at least 1
/// (a lower bound in voxels). Exactness is what makes distance skipping safe: no occupied cell lies
/// within (d - 1) cells of any point of a cell at distance d (lighting.glsl's empty_radius).
std::vector<uint8_t> occupancy_distance(const std::vector<uint8_t>& occ, const std::array<int, 3>& n, bool tiles,
                                        const std::array<int, 3>& dims, int cell);

/// Cells of the moved grid per static cell, kMovedCellVoxels (8) voxels / occ_cell, at least 1; 1
/// without a distance field (the padded grid then marks what is near density).
int moved_reach_cells(const PreparedVolume& vol);
/// PreparedVolume::moved_near_sat for `reach` (the cells with dist <= reach, or occ != 0 without
/// a distance field or with use_dist false).
std::vector<uint32_t> moved_near_table(const PreparedVolume& vol, int reach, bool use_dist = true);

}  // namespace cloudviewer
