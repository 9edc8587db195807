// Scale-out: building the one-process VDB from bricks generated elsewhere (MPI ranks) or from
// tile files (farm jobs), without ever holding a dense copy of the whole volume.
// No OpenVDB types here: the implementation lives in src/scale/vdb_merge.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"

namespace cloudgen {

/// The VDB grids of a volume, filled brick by brick or tile by tile in any order, then written
/// with the same grid settings, transform, metadata and file options as write_vdb. The result
/// has the same grids, active voxels and values as write_vdb of the dense volume.
class VdbAssembler {
 public:
  /// `header`: dims, origin, voxel size and metadata of the output (volume_header()); its detail
  /// vectors are ignored, `detail[c]` says whether detail grid c is written (as write_vdb would
  /// for a volume whose channel c was generated).
  VdbAssembler(const Volume& header, const std::array<bool, 3>& detail, const ExportOptions& o);
  ~VdbAssembler();
  VdbAssembler(const VdbAssembler&) = delete;
  VdbAssembler& operator=(const VdbAssembler&) = delete;

  /// Adds the box [lo, hi) of the header's voxels; each channel is x fastest over the box, or
  /// null / empty for all 0. Boxes must not overlap. Not thread-safe.
  void add(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi, const float* density,
           const std::array<const float*, 3>& detail);
  /// Adds every active voxel of the density and detail grids of a VDB cloudgen wrote, whose voxel
  /// (0,0,0) is the header's voxel `offset`. Throws InputError naming the file when unreadable.
  void add_vdb(const std::string& path, const std::array<uint32_t, 3>& offset);
  /// Prunes and writes the VDB atomically (may be called for several paths).
  void write(const std::string& path);
  /// Active voxels of the density grid so far (after baking the erosion, when it is baked).
  uint64_t active_voxels() const;
  /// Voxels of density > 0 that add() received, before any baking: the count the one-process
  /// run's --stats reports as active.
  uint64_t generated_voxels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// What cloudgen recorded in a VDB: the density grid's metadata, the grid names, the voxel size
/// and the world position of voxel (0,0,0)'s min corner. Throws InputError naming the file.
struct VdbHeader {
  std::vector<std::pair<std::string, std::string>> metadata;
  std::vector<std::string> grids;
  double voxel_size = 0;
  std::array<double, 3> origin{};
  std::string meta(const std::string& key) const;
};
VdbHeader read_vdb_header(const std::string& path);

/// FNV-1a 64 of a file's bytes as 16 hex digits (tile checksums; detects damage, not tampering).
/// In an OpenVDB file the random per-write UUID is left out, so the same tile generated again
/// has the same checksum. Throws IoError naming the file when it cannot be read.
std::string file_checksum(const std::string& path);

/// Splits plan bricks over `parts` workers by expected cost (longest first onto the least loaded;
/// ties by index), deterministic. Returns each part's brick indices in plan order.
std::vector<std::vector<size_t>> balance_bricks(const BrickPlan& plan, int parts);

}  // namespace cloudgen
