// OpenVDB export and import: the only translation unit that includes OpenVDB (its headers take
// 15-25 s to compile).
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Prune.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <mutex>
#include <sstream>

#include "cloudgen/io.h"
#include "vdb_internal.h"

namespace cloudgen {
namespace vdb {

void init() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr make_transform(const Volume& v) {
  auto xf = openvdb::math::Transform::createLinearTransform(v.voxel_size);
  xf->postTranslate(openvdb::Vec3d(v.origin[0] + 0.5 * v.voxel_size, v.origin[1] + 0.5 * v.voxel_size,
                                   v.origin[2] + 0.5 * v.voxel_size));
  return xf;
}

openvdb::FloatGrid::Ptr make_empty_grid(const Volume& v, const std::string& name, bool half) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName(name);
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  grid->setTransform(make_transform(v));
  grid->setSaveFloatAsHalf(half);
  return grid;
}

openvdb::FloatGrid::Ptr make_grid(const Volume& v, const std::vector<float>& data, const std::string& name,
                                  bool half) {
  auto grid = make_empty_grid(v, name, half);
  // Wrap our x-fastest buffer (no copy) and let OpenVDB's threaded copy activate every voxel
  // that differs from the background 0 (densities are >= 0, so exactly the cloud voxels).
  const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(int(v.dims[0]) - 1, int(v.dims[1]) - 1,
                                                                 int(v.dims[2]) - 1));
  openvdb::tools::Dense<const float, openvdb::tools::LayoutXYZ> dense(box, data.data());
  openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  openvdb::tools::prune(grid->tree());
  return grid;
}

openvdb::GridPtrVec make_empty_grids(const Volume& v, const ExportOptions& o) {
  openvdb::GridPtrVec grids{make_empty_grid(v, "density", o.vdb_half)};
  if (o.vdb_detail)
    for (int c = 0; c < 3; ++c)
      if (!v.detail[c].empty()) grids.push_back(make_empty_grid(v, v.detail_names[c], o.vdb_half));
  return grids;
}

void write_grids(const Volume& v, const openvdb::GridPtrVec& grids, const std::string& path, const ExportOptions& o) {
  // Both the one-process writer and the MPI / tile assembler end here: a change to the grids'
  // topology, transform or metadata made here reaches every path's output alike.
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);
  for (auto& [k, val] : v.metadata) density->insertMeta(k, openvdb::StringMetadata(val));
  // Never a creator starting with "Houdini": Blender then assumes a Y-up Houdini file and rotates it.
  density->setCreator(std::string("cloudgen ") + CLOUDGEN_VERSION);
  atomic_write(path, [&](const std::string& tmp) {
    openvdb::io::File file(tmp);
    uint32_t comp = openvdb::io::COMPRESS_ACTIVE_MASK;
    if (o.vdb_compression == "blosc") comp |= openvdb::io::COMPRESS_BLOSC;
    else if (o.vdb_compression == "zip") comp |= openvdb::io::COMPRESS_ZIP;
    else if (o.vdb_compression != "none")
      throw InputError("export.vdb.compression: \"" + o.vdb_compression + "\" is not one of blosc, zip, none");
    if ((comp & openvdb::io::COMPRESS_BLOSC) && !openvdb::io::Archive::hasBloscCompression()) {
      comp = openvdb::io::COMPRESS_ACTIVE_MASK | openvdb::io::COMPRESS_ZIP;
    }
    file.setCompression(comp);
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("cloudgen ") + CLOUDGEN_VERSION));
    file.write(grids, meta);
    file.close();
  });
}

}  // namespace vdb

namespace {

using vdb::make_grid;
void init_vdb() { vdb::init(); }

void open_or_throw(openvdb::io::File& file, const std::string& path) {
  init_vdb();
  try {
    file.open();
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": not a readable OpenVDB file (" + e.what() + ")");
  }
}

}  // namespace

void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o) {
  init_vdb();
  // The density grid and the detail grids are built in parallel.
  std::vector<std::pair<const std::vector<float>*, std::string>> todo{{&v.density, "density"}};
  if (o.vdb_detail)
    for (int c = 0; c < 3; ++c)
      if (!v.detail[c].empty()) todo.push_back({&v.detail[c], v.detail_names[c]});
  openvdb::GridPtrVec grids(todo.size());
  tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) {
    grids[i] = make_grid(v, *todo[i].first, todo[i].second, o.vdb_half);
  });
  vdb::write_grids(v, grids, path, o);
}

Volume read_vdb(const std::string& path) {
  init_vdb();
  openvdb::io::File file(path);
  open_or_throw(file, path);
  openvdb::GridBase::Ptr base;
  std::vector<std::string> names;
  for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
  if (std::find(names.begin(), names.end(), "density") == names.end()) {
    std::string have;
    for (auto& n : names) have += (have.empty() ? "" : ", ") + n;
    throw InputError(path + ": no float grid named \"density\" (grids: " + (have.empty() ? "none" : have) + ")");
  }
  base = file.readGrid("density");
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw InputError(path + ": grid \"density\" is " + base->valueType() + ", expected float");
  if (!grid->transform().isLinear() || !grid->hasUniformVoxels())
    throw InputError(path + ": grid \"density\" needs a linear transform with cubic voxels");
  Volume v;
  openvdb::CoordBBox bb = grid->evalActiveVoxelBoundingBox();
  if (bb.empty()) throw InputError(path + ": grid \"density\" has no active voxels");
  const openvdb::Coord lo = bb.min(), dim = bb.dim();
  const uint64_t count = uint64_t(dim.x()) * dim.y() * dim.z();
  if (count > (uint64_t(1) << 31)) throw InputError(path + ": active bounding box too large to load densely");
  for (int a = 0; a < 3; ++a) v.dims[a] = uint32_t(dim[a]);
  v.voxel_size = grid->voxelSize()[0];
  const openvdb::Vec3d w = grid->indexToWorld(lo.asVec3d());
  for (int a = 0; a < 3; ++a) v.origin[a] = w[a] - 0.5 * v.voxel_size;
  auto fill = [&](const openvdb::FloatGrid& g, std::vector<float>& out) {
    out.assign(v.voxel_count(), 0.0f);
    for (auto it = g.cbeginValueOn(); it; ++it) {
      openvdb::CoordBBox vb;
      it.getBoundingBox(vb);
      vb.intersect(bb);
      // Detail grids reach beyond the density's bounding box; an empty intersection's iterator
      // would still visit coordinates, so skip it.
      if (vb.empty()) continue;
      for (auto c = vb.begin(); c; ++c) {
        const openvdb::Coord q = *c - lo;
        out[v.index(uint32_t(q.x()), uint32_t(q.y()), uint32_t(q.z()))] = *it;
      }
    }
  };
  fill(*grid, v.density);
  for (int c = 0; c < 3; ++c)
    if (std::find(names.begin(), names.end(), v.detail_names[c]) != names.end())
      if (auto d = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(v.detail_names[c]))) fill(*d, v.detail[c]);
  for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it)
    if (it->first.rfind("file_", 0) != 0 && it->first != "class" && it->first != "name")
      v.metadata.push_back({it->first, it->second->str()});
  file.close();
  build_occupancy(v);
  return v;
}

std::string describe_vdb(const std::string& path) {
  init_vdb();
  openvdb::io::File file(path);
  open_or_throw(file, path);
  std::ostringstream o;
  o << path << " (OpenVDB, compression " << openvdb::io::compressionToString(file.compression()) << ")\n";
  auto fmeta = file.getMetadata();
  for (auto it = fmeta->beginMeta(); it != fmeta->endMeta(); ++it) o << "  file " << it->first << ": " << it->second->str() << "\n";
  for (auto it = file.beginName(); it != file.endName(); ++it) {
    auto g = file.readGrid(it.gridName());
    o << "  grid \"" << g->getName() << "\": " << g->valueType() << ", class "
      << openvdb::GridBase::gridClassToString(g->getGridClass()) << ", voxel size " << g->voxelSize()[0]
      << ", active voxels " << g->activeVoxelCount() << ", saved as " << (g->saveFloatAsHalf() ? "half" : "float")
      << "\n";
    openvdb::CoordBBox bb = g->evalActiveVoxelBoundingBox();
    if (!bb.empty()) {
      openvdb::Vec3d wlo = g->indexToWorld(bb.min().asVec3d() - openvdb::Vec3d(0.5)),
                     whi = g->indexToWorld(bb.max().asVec3d() + openvdb::Vec3d(0.5));
      o << "    index bbox " << bb.min() << " .. " << bb.max() << ", world bbox " << wlo << " .. " << whi << "\n";
    }
    if (auto fg = openvdb::gridPtrCast<openvdb::FloatGrid>(g)) {
      float lo = 1e30f, hi = -1e30f;
      for (auto v = fg->cbeginValueOn(); v; ++v) lo = std::min(lo, *v), hi = std::max(hi, *v);
      if (fg->activeVoxelCount()) o << "    values min " << lo << ", max " << hi << ", background " << fg->background() << "\n";
    }
    for (auto m = g->beginMeta(); m != g->endMeta(); ++m)
      if (m->first.rfind("file_", 0) != 0) o << "    " << m->first << ": " << m->second->str() << "\n";
  }
  return o.str();
}

}  // namespace cloudgen
