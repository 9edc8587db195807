// NanoVDB (.nvdb): the sparse grids cloudgen writes, read back without densifying, for renderers
// that march the tree itself (cloudviewer's render.volume=nanovdb, through PNanoVDB.h). No
// OpenVDB or NanoVDB headers here: only src/io/nvdb_io.cpp sees them.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cloudgen/export_options.h"
#include "cloudgen/volume.h"

namespace cloudgen {

/// NanoVDB float grids in one buffer, back to back, each starting on a 32-byte boundary (the
/// layout a shader storage buffer takes as is). grids[0] is "density"; detail[c] indexes the grid
/// of v.detail_names[c], -1 when the file has none. Voxel (i,j,k) of the volume is index
/// index_min + (i,j,k) of every grid (the density's active bounding box starts at index_min).
struct NanoVolume {
  struct Grid {
    std::string name;
    uint64_t offset = 0;  ///< bytes from the start of the buffer
    uint64_t bytes = 0;
    uint64_t active_voxels = 0;  ///< every active tile counted as the voxels it covers (saturating)
    uint32_t leaves = 0, lower = 0, upper = 0;  ///< node counts
    /// How the file stored it (export.nvdb.precision's names): "float", or "fp16", "fp8", "fp4",
    /// "fpn" for NanoVDB's quantised leaves, decoded to float on reading.
    std::string precision = "float";
  };
  struct alignas(32) Block {
    uint8_t b[32];
  };
  std::vector<Block> buffer;
  std::vector<Grid> grids;
  std::array<int, 3> detail{{-1, -1, -1}};
  std::array<int32_t, 3> index_min{{0, 0, 0}};
  std::array<uint32_t, 3> dims{{0, 0, 0}};  ///< the density's active bounding box, voxels
  double voxel_size = 1;
  std::array<double, 3> origin{{0, 0, 0}};  ///< min corner of voxel index_min, y-up metres
  bool tiles_xz = false;
  char up = 'y';
  /// The three detail grids have one node layout (cloudgen writes them on one mask): a value's
  /// byte offset in detail grid 1 plus the grids' distance is the same voxel's in grids 2 and 3,
  /// so a renderer walks one tree for all three.
  bool detail_shared_layout = false;
  std::vector<std::pair<std::string, std::string>> metadata;

  /// The blocks as one byte array (null when empty): grid offsets count from here. Not from
  /// `front().b`: arithmetic past that 32-byte member array is out of bounds.
  const uint8_t* data() const { return buffer.empty() ? nullptr : reinterpret_cast<const uint8_t*>(buffer.data()); }
  uint8_t* data() { return buffer.empty() ? nullptr : reinterpret_cast<uint8_t*>(buffer.data()); }
  uint64_t bytes() const { return uint64_t(buffer.size()) * sizeof(Block); }
  bool has_detail() const { return detail[0] >= 0 && detail[1] >= 0 && detail[2] >= 0; }
};

/// A renderer's shortcut past the tree walk: one entry per 8^3 leaf cell of grid g's index
/// lattice over the volume's box (cell (0,0,0) starts at index `origin`, a multiple of 8). An entry
/// is the 32-bit word index (byte offset / 4 in NanoVolume::buffer) of the cell's leaf's value
/// array, to which the voxel's leaf offset ((x&7)<<6 | (y&7)<<3 | z&7) is added; or kNanoConstant
/// | the word index of the one value the whole cell reads (a tile's, or the background). Built by
/// walking the tree once per cell; its size is the box's voxels / 128 bytes.
struct NanoPages {
  static constexpr uint32_t kNanoConstant = 0x80000000u;
  std::array<int32_t, 3> origin{{0, 0, 0}};
  std::array<uint32_t, 3> dims{{0, 0, 0}};
  std::vector<uint32_t> entries;  ///< x fastest
};
NanoPages nano_pages(const NanoVolume& n, size_t grid);

/// The grids write_nvdb writes for v (the .vdb export's grids, options and metadata), in memory.
NanoVolume nano_from_volume(const Volume& v, const ExportOptions& o = ExportOptions{});
/// A .vdb file's density and detail grids converted to NanoVDB without a dense copy (the same
/// checked reader and refusals as read_vdb; physical densities scaled back to normalised).
NanoVolume nano_from_vdb(const std::string& path);
/// Reads a .nvdb file (uncompressed NanoVDB float, Fp16, Fp8, Fp4 or FpN grids with a "density"
/// grid; quantised grids decoded to float, their precision in Grid::precision): every size,
/// offset and node link checked against the file, so a damaged file gives InputError naming the
/// file and what is wrong, never a crash. Physical densities are scaled back to normalised.
NanoVolume read_nvdb(const std::string& path);
/// Reads a .nvdb file from memory (`name` labels the errors); what read_nvdb and the fuzzer call.
NanoVolume parse_nvdb(const uint8_t* data, size_t size, const std::string& name);
/// Dense channels of a NanoVolume (what read_volume returns for .nvdb); InputError beyond max_bytes.
Volume dense_from_nano(const NanoVolume& n, uint64_t max_bytes, const std::string& name);
/// Value of grid g at index ijk (0 outside its active voxels): a NanoVDB read accessor, for tests.
float nano_value(const NanoVolume& n, size_t g, const std::array<int32_t, 3>& ijk);
/// Occupancy of the density grid's active leaves and tiles holding values > 0 on the volume's
/// lattice of `cell`^3-voxel cells, dilated by `padding` cells (26-neighbourhood, wrapped in x/z
/// when tiling): cloudgen::build_occupancy's rule, conservative at leaf granularity (a leaf
/// marks every cell its voxels > 0 touch), never a dense copy. x fastest.
std::vector<uint8_t> nano_occupancy(const NanoVolume& n, uint32_t cell, uint32_t padding,
                                    std::array<uint32_t, 3>& occ_dims);

}  // namespace cloudgen
