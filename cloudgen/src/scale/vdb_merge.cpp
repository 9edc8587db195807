// Assembling the one-process VDB from bricks (MPI ranks) or tile files (farm jobs). The grids are
// made, stamped and written by the same functions as write_vdb (vdb_internal.h); only the way
// voxels arrive differs: here sparse, box by box, never as a dense copy of the volume.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>

#include <tbb/parallel_for.h>

#include <algorithm>

#include "cloudgen/erosion.h"
#include "cloudgen/motion.h"
#include "cloudgen/scale.h"
#include "cloudgen/view.h"
#include "io/vdb_internal.h"
#include "cloudgen/input_scope.h"

namespace cloudgen {

struct VdbAssembler::Impl {
  Volume header;
  ExportOptions options;
  openvdb::GridPtrVec grids;                        // as write_vdb orders them
  std::array<openvdb::FloatGrid::Ptr, 4> channel;   // density, detail g/b/a (null when not written)
  bool pruned = false;
  // export.vdb.bake_erosion: bricks arrive with their detail channels and leave eroded density,
  // as export_grids bakes the dense volume (the same eroded_density, the same height box).
  bool bake = false;
  double erosion = 0;           // the look's erosion (recorded as erosion_baked)
  double box_y0 = 0, box_ny = 1;  // the height box in the header's voxels
  uint64_t generated = 0;         // voxels of density > 0 added by add(), before any baking
};

VdbAssembler::VdbAssembler(const Volume& header, const std::array<bool, 3>& detail, const ExportOptions& o)
    : impl_(std::make_unique<Impl>()) {
  vdb::init();
  impl_->header = header;
  impl_->options = o;
  // make_empty_grids decides which detail grids exist from non-empty detail vectors: mark the
  // generated ones with one element (never read).
  Volume marks = header;
  for (int c = 0; c < 3; ++c) marks.detail[c].assign(detail[c] ? 1 : 0, 0.0f);
  impl_->grids = vdb::make_empty_grids(marks, o);
  impl_->channel[0] = openvdb::gridPtrCast<openvdb::FloatGrid>(impl_->grids[0]);
  size_t g = 1;
  if (o.vdb_detail && !o.vdb_bake_erosion)
    for (int c = 0; c < 3; ++c)
      if (detail[c]) impl_->channel[c + 1] = openvdb::gridPtrCast<openvdb::FloatGrid>(impl_->grids[g++]);
  const bool all_detail = detail[0] && detail[1] && detail[2];
  const Look look = look_of_view(view_of_metadata(header.metadata, "the assembled VDB"), "the assembled VDB");
  impl_->erosion = all_detail ? look.erosion : 0.0;
  if (o.vdb_bake_erosion && all_detail && look.erosion > 0) {
    double min_y = 0, height = 0;
    if (!motion_height_box(header.metadata, min_y, height))
      throw std::logic_error("VdbAssembler: the volume header records no height box (motion.box_min_y)");
    impl_->bake = true;
    impl_->box_y0 = (min_y - header.origin[1]) / header.voxel_size;
    impl_->box_ny = height / header.voxel_size;
  }
}

VdbAssembler::~VdbAssembler() = default;

void VdbAssembler::add(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi, const float* density,
                       const std::array<const float*, 3>& detail) {
  const float* src[4] = {density, detail[0], detail[1], detail[2]};
  if (density) {
    const size_t count = size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    impl_->generated += uint64_t(std::count_if(density, density + count, [](float d) { return d > 0; }));
  }
  std::vector<float> baked;
  if (impl_->bake && density) {
    if (!detail[0] || !detail[1] || !detail[2])
      throw std::logic_error("VdbAssembler::add: baking the erosion needs the brick's three detail channels");
    baked.resize(size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]));
    size_t k = 0;
    for (uint32_t z = lo[2]; z < hi[2]; ++z)
      for (uint32_t y = lo[1]; y < hi[1]; ++y)
        for (uint32_t x = lo[0]; x < hi[0]; ++x, ++k)
          baked[k] = float(eroded_density(density[k], detail[0][k], detail[1][k], detail[2][k],
                                          (double(y) - impl_->box_y0 + 0.5) / impl_->box_ny, impl_->erosion));
    src[0] = baked.data();
  }
  // The channels are separate grids, so they are filled in parallel.
  tbb::parallel_for(0, 4, [&](int c) {
    if (!impl_->channel[c] || !src[c]) return;
    // Same rule as copyFromDense with tolerance 0 in write_vdb: a voxel is active iff it is not
    // the background 0; pruning at the end gives the same tree.
    auto acc = impl_->channel[c]->getAccessor();
    size_t k = 0;
    for (uint32_t z = lo[2]; z < hi[2]; ++z)
      for (uint32_t y = lo[1]; y < hi[1]; ++y)
        for (uint32_t x = lo[0]; x < hi[0]; ++x, ++k)
          if (src[c][k] != 0.0f) acc.setValueOn(openvdb::Coord(int(x), int(y), int(z)), src[c][k]);
  });
  impl_->pruned = false;
}

namespace {

openvdb::io::File& open_file(openvdb::io::File& f, const std::string& path) {
  protect_input(path, "the tile " + path);
  vdb::init();
  vdb::vet_vdb(path);
  try {
    f.open();
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": not a readable OpenVDB file (" + e.what() + ")");
  }
  return f;
}

}  // namespace

void VdbAssembler::add_vdb(const std::string& path, const std::array<uint32_t, 3>& offset) {
  openvdb::io::File file(path);
  open_file(file, path);
  const std::string names[4] = {"density", impl_->header.detail_names[0], impl_->header.detail_names[1],
                                impl_->header.detail_names[2]};
  const openvdb::Coord off(static_cast<int>(offset[0]), static_cast<int>(offset[1]), static_cast<int>(offset[2]));
  try {
    for (int c = 0; c < 4; ++c) {
      if (!impl_->channel[c]) continue;
      if (!file.hasGrid(names[c])) throw InputError(path + ": no grid \"" + names[c] + "\"");
      auto tile = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(names[c]));
      if (!tile) throw InputError(path + ": grid \"" + names[c] + "\" is not a float grid");
      auto acc = impl_->channel[c]->getAccessor();
      for (auto it = tile->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
          acc.setValueOn(it.getCoord() + off, *it);
        } else {
          openvdb::CoordBBox bb;
          it.getBoundingBox(bb);
          for (auto q = bb.begin(); q; ++q) acc.setValueOn(*q + off, *it);
        }
      }
    }
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": damaged OpenVDB file (" + e.what() + ")");
  }
  file.close();
  impl_->pruned = false;
}

void VdbAssembler::write(const std::string& path) {
  if (!impl_->pruned)
    for (auto& g : impl_->channel)
      if (g) openvdb::tools::prune(g->tree());
  impl_->pruned = true;
  OutputBatch batch;
  vdb::write_grids(impl_->header, impl_->grids, path, impl_->options, batch, impl_->erosion);
  batch.commit();
}

uint64_t VdbAssembler::active_voxels() const { return impl_->channel[0]->activeVoxelCount(); }
uint64_t VdbAssembler::generated_voxels() const { return impl_->generated; }

std::string VdbHeader::meta(const std::string& key) const {
  for (const auto& [k, v] : metadata)
    if (k == key) return v;
  return "";
}

VdbHeader read_vdb_header(const std::string& path) {
  openvdb::io::File file(path);
  open_file(file, path);
  VdbHeader h;
  try {
    for (auto it = file.beginName(); it != file.endName(); ++it) h.grids.push_back(it.gridName());
    if (std::find(h.grids.begin(), h.grids.end(), "density") == h.grids.end())
      throw InputError(path + ": no grid \"density\"");
    auto g = file.readGridMetadata("density");
    for (auto it = g->beginMeta(); it != g->endMeta(); ++it)
      if (it->first.rfind("file_", 0) != 0 && it->first != "class" && it->first != "name")
        h.metadata.push_back({it->first, it->second->str()});
    h.voxel_size = g->voxelSize()[0];
    // The origin in the y-up frame whichever way the file stands (export.vdb.up).
    const char up = vdb::up_axis_of(g->transform(), path);
    const openvdb::Vec3d w = vdb::to_y_up(g->indexToWorld(openvdb::Vec3d(0.0)), up);
    for (int a = 0; a < 3; ++a) h.origin[a] = w[a] - 0.5 * h.voxel_size;
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": damaged OpenVDB file (" + e.what() + ")");
  }
  file.close();
  return h;
}

}  // namespace cloudgen
