// One frame of a baked motion sequence as a .vdb: write_vdb's grids of the displaced channels, a
// "velocity" vector grid for motion blur, and the frame's time and motion in the metadata.
// Includes OpenVDB (slow to compile): kept apart from sequence.cpp.
#include <openvdb/openvdb.h>
#include <openvdb/tree/LeafManager.h>

#include "cloudgen/sequence.h"
#include "io/vdb_internal.h"

namespace cloudgen {

void write_vdb_frame(const MotionFrame& f, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
  double erosion = 0;
  openvdb::GridPtrVec grids = vdb::export_grids(f.volume, path, o, &erosion);
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);

  // Velocity dD/dt on the density's active voxels. D depends on the row only, so each voxel takes
  // its row's vector, turned into the file's frame like the positions (up = z: (x, y, z) -> (x, -z, y)).
  auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  vel->setName("velocity");
  vel->setTransform(density->transform().copy());
  vel->setGridClass(openvdb::GRID_UNKNOWN);
  vel->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
  vel->setIsInWorldSpace(true);
  vel->setSaveFloatAsHalf(o.vdb_half);
  vel->tree().topologyUnion(density->tree());
  vel->tree().voxelizeActiveTiles();
  std::vector<openvdb::Vec3s> rows(f.row_velocity.size());
  for (size_t j = 0; j < rows.size(); ++j) {
    const glm::dvec3& w = f.row_velocity[j];
    rows[j] = o.vdb_up == 'z' ? openvdb::Vec3s(float(w.x), float(-w.z), float(w.y))
                              : openvdb::Vec3s(float(w.x), float(w.y), float(w.z));
  }
  openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(vel->tree());
  leaves.foreach([&](openvdb::Vec3STree::LeafNodeType& leaf, size_t) {
    for (auto it = leaf.beginValueOn(); it; ++it) {
      const int y = it.getCoord().y();  // index y = the frame's row (the up = z turn is in the transform)
      if (y >= 0 && size_t(y) < rows.size()) it.setValue(rows[size_t(y)]);
    }
  });
  vel->insertMeta("units", openvdb::StringMetadata("metres per second, world space of this file"));
  vel->insertMeta("method", openvdb::StringMetadata("central difference of motion_displacement, step +-" +
                                                    std::to_string(kVelocityStep) + " s"));
  grids.push_back(vel);

  // The frame's time and the motion that made it (typed, so Houdini and Python read numbers).
  density->insertMeta("frame", openvdb::Int64Metadata(f.frame));
  density->insertMeta("time_seconds", openvdb::DoubleMetadata(f.time));
  density->insertMeta("fps", openvdb::DoubleMetadata(f.fps));
  density->insertMeta("frame_first", openvdb::Int64Metadata(f.range.first));
  density->insertMeta("frame_last", openvdb::Int64Metadata(f.range.last));
  density->insertMeta("motion.loop", openvdb::BoolMetadata(f.loop));
  for (const MotionKey& k : motion_keys())
    density->insertMeta("motion." + k.key, openvdb::DoubleMetadata(f.motion.*k.member));
  density->insertMeta(std::string("motion.") + kFlowMapKey, openvdb::StringMetadata(flow_map_name(f.motion)));
  if (f.motion.flow_map)
    density->insertMeta("motion.flow_map_fnv1a", openvdb::StringMetadata(std::to_string(f.motion.flow_map->fnv1a)));
  density->insertMeta("motion.box_min_y", openvdb::DoubleMetadata(f.box.min_y()));
  density->insertMeta("motion.box_height", openvdb::DoubleMetadata(f.box.height()));
  vdb::write_grids(f.volume, grids, path, o, batch, erosion);
}

}  // namespace cloudgen
