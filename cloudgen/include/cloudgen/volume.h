// The in-memory cloud volume that cloudgen produces and every exporter and the viewer consume.
// Plain data, no OpenVDB types: OpenVDB is confined to cloudgen/src/io/vdb_io.cpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "cloudgen/errors.h"

namespace cloudgen {

/// Dense channels in memory order x fastest, then y, then z: index = (z * dims.y + y) * dims.x + x.
/// Voxel (i, j, k) covers world box origin + voxel_size * [i, i+1) x [j, j+1) x [k, k+1); its value
/// is the density at the voxel centre. y is up (height).
struct Volume {
  std::array<uint32_t, 3> dims{{0, 0, 0}};
  double voxel_size = 1.0;                   ///< metres per voxel
  std::array<double, 3> origin{{0, 0, 0}};   ///< world position of voxel (0,0,0)'s min corner, metres
  bool tiles_xz = false;                     ///< true when x and z wrap seamlessly (layer mode)

  /// R: shaped cloud density in [0, 1] (after height profile, towers, coverage and threshold).
  std::vector<float> density;
  /// G, B, A: detail noise in [0, 1] at higher frequencies, used to erode edges at render time.
  /// Each is empty when not generated.
  std::array<std::vector<float>, 3> detail;
  std::array<std::string, 3> detail_names{{"detail_g", "detail_b", "detail_a"}};

  /// Occupancy: coarse grid, 1 where the coarse cell or a neighbour within `occupancy_padding`
  /// cells holds any non-zero density voxel. Cell (i,j,k) covers voxels [i*c, (i+1)*c) per axis,
  /// c = occupancy_cell. Same memory order as the channels. Empty when not computed.
  uint32_t occupancy_cell = 8;
  uint32_t occupancy_padding = 2;
  std::array<uint32_t, 3> occupancy_dims{{0, 0, 0}};
  std::vector<uint8_t> occupancy;

  /// Free-form provenance: preset name, seed, generator version...
  std::vector<std::pair<std::string, std::string>> metadata;

  size_t voxel_count() const { return size_t(dims[0]) * dims[1] * dims[2]; }
  size_t index(uint32_t x, uint32_t y, uint32_t z) const {
    return (size_t(z) * dims[1] + y) * dims[0] + x;
  }
  std::array<double, 3> world_size() const {
    return {dims[0] * voxel_size, dims[1] * voxel_size, dims[2] * voxel_size};
  }
};

/// Builds the occupancy grid of `v.density` with v.occupancy_cell / v.occupancy_padding.
/// Wraps the dilation around x and z when v.tiles_xz.
void build_occupancy(Volume& v);
/// build_occupancy of a dense density array (x fastest, `dims`): the grid's cells, their counts in
/// `od`. The viewer builds its grid straight from a volume it does not own with it.
std::vector<uint8_t> occupancy_cells(const float* density, const std::array<uint32_t, 3>& dims, uint32_t cell,
                                     uint32_t padding, bool tiles_xz, std::array<uint32_t, 3>& od);
/// build_occupancy's dilation: cells (od, x fastest) dilated by `padding` cells per axis (the
/// union over the (2p+1)^3 box), wrapped in x and z when `tiles_xz`.
void dilate_occupancy(std::vector<uint8_t>& cells, const std::array<uint32_t, 3>& od, uint32_t padding, bool tiles_xz);

/// Memory a reader may use for the dense volume unless told otherwise (16 GiB).
inline constexpr uint64_t kDefaultReadBudget = uint64_t(16) << 30;

/// Reads any volume cloudgen writes: `.vdb` (grid `density`, optional detail grids), a raw texture
/// (`.raw` with its `.json` sidecar, or the sidecar itself), or `.ktx2`. Throws InputError with the
/// path and what is wrong (missing file, no `density` grid, wrong size...).
/// An input whose dense channels would need more than `max_bytes` is refused (InputError with the
/// estimate) before anything large is allocated.
Volume read_volume(const std::string& path, uint64_t max_bytes = kDefaultReadBudget);

}  // namespace cloudgen
