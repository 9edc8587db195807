// OpenVDB pieces shared by the one-process writer (vdb_io.cpp) and the brick/tile assembler
// (vdb_merge.cpp), so both paths make their grids, transform, metadata and file with the same code.
// Internal: includes OpenVDB, so only those two translation units include it.
#pragma once

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

#include "cloudgen/io.h"

namespace cloudgen::vdb {

void init();
/// Voxel (i,j,k) covers [origin + i*vs, origin + (i+1)*vs): its centre, index (i,j,k) in OpenVDB,
/// sits at origin + (i + 0.5) * vs.
openvdb::math::Transform::Ptr make_transform(const Volume& v);
/// A grid with v's name, class, transform and storage settings and no voxels.
openvdb::FloatGrid::Ptr make_empty_grid(const Volume& v, const std::string& name, bool half);
/// The grid of a dense channel of v: every non-zero voxel active, pruned.
openvdb::FloatGrid::Ptr make_grid(const Volume& v, const std::vector<float>& data, const std::string& name, bool half);
/// The grids write_vdb writes for v (density first, then the detail grids), as empty grids.
openvdb::GridPtrVec make_empty_grids(const Volume& v, const ExportOptions& o);
/// Writes grids (density first) with v's metadata and creator to `path`, atomically.
void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o);

}  // namespace cloudgen::vdb
