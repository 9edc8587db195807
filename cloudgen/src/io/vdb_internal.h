// OpenVDB pieces shared by the one-process writer (vdb_io.cpp) and the brick/tile assembler
// (vdb_merge.cpp), so both paths make their grids, transform, metadata and file with the same code.
// Internal: includes OpenVDB, so only those two translation units include it.
#pragma once

#include <openvdb/openvdb.h>

#include <set>
#include <string>
#include <vector>

#include "cloudgen/io.h"

namespace cloudgen::vdb {

void init();
/// Voxel (i,j,k) covers [origin + i*vs, origin + (i+1)*vs): its centre, index (i,j,k) in OpenVDB,
/// sits at origin + (i + 0.5) * vs (y-up); up = 'z' turns the world +90 degrees about x.
openvdb::math::Transform::Ptr make_transform(const Volume& v, char up = 'y');
/// The file's world frame back to the y-up frame.
openvdb::Vec3d to_y_up(const openvdb::Vec3d& w, char up);
/// 'y' or 'z' from the grid transform; InputError for other rotations and shears.
char up_axis_of(const openvdb::math::Transform& xf, const std::string& path);
/// A grid with v's name, class, transform and storage settings and no voxels.
openvdb::FloatGrid::Ptr make_empty_grid(const Volume& v, const std::string& name, bool half, char up = 'y');
/// The grid of a dense channel of v: every non-zero voxel active, pruned.
openvdb::FloatGrid::Ptr make_grid(const Volume& v, const std::vector<float>& data, const std::string& name, bool half,
                                  char up = 'y');
/// The grids write_vdb writes for v (density first, then the detail grids), as empty grids.
openvdb::GridPtrVec make_empty_grids(const Volume& v, const ExportOptions& o);
/// Stages grids (density first; detail grids get the density's topology dilated by one voxel)
/// with the computed metadata (extinction, voxel size, phase, up axis, tiling, units), v's
/// metadata and the creator, in `batch`. `erosion_baked`: the erosion applied to density, or < 0
/// when the grids were assembled from bricks (then bake_erosion is refused).
void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o,
                 OutputBatch& batch, double erosion_baked);
/// write_grids without the file: the detail topology, physical scale and metadata on `grids`.
void finish_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o,
                  double erosion_baked);
/// The grids write_vdb writes for v, before finish_grids (density first, erosion baked if asked,
/// then the detail grids); `erosion_baked` (may be null) receives the erosion write_grids records.
/// `path` names v in messages.
openvdb::GridPtrVec export_grids(const Volume& v, const std::string& path, const ExportOptions& o,
                                 double* erosion_baked);
/// Every grid of a .vdb file through the checked reader read_vdb uses (InputError when damaged).
openvdb::GridPtrVec read_grids(const std::string& path);
/// The seal cloudgen writes as a .vdb's file UUID, from the file's other bytes (vdb_io.cpp).
std::string file_seal(const std::string& path);
/// Before OpenVDB reads a .vdb's grids: its layout walked, then the seal checked, or the file read
/// once in a child process under a memory limit; InputError if it is damaged (vdb_io.cpp).
void vet_vdb(const std::string& path);
/// Linear transform with cubic voxels.
bool cubic_voxels(const openvdb::GridBase& g);
/// Metadata keys write_grids computes (never copied from Volume::metadata).
const std::set<std::string>& computed_meta();
/// The same, written at once (all or nothing).
void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o);

}  // namespace cloudgen::vdb
