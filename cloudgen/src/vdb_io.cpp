// OpenVDB export and import: the only translation unit that includes OpenVDB (its headers take
// 15-25 s to compile).
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Prune.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>

#include "cloudgen/io.h"

namespace cloudgen {
namespace {

void init_vdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// Voxel (i,j,k) covers [origin + i*vs, origin + (i+1)*vs): its centre, index (i,j,k) in OpenVDB,
/// sits at origin + (i + 0.5) * vs.
openvdb::math::Transform::Ptr make_transform(const Volume& v) {
  auto xf = openvdb::math::Transform::createLinearTransform(v.voxel_size);
  xf->postTranslate(openvdb::Vec3d(v.origin[0] + 0.5 * v.voxel_size, v.origin[1] + 0.5 * v.voxel_size,
                                   v.origin[2] + 0.5 * v.voxel_size));
  return xf;
}

openvdb::FloatGrid::Ptr make_grid(const Volume& v, const std::vector<float>& data, const std::string& name,
                                  bool half) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName(name);
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  grid->setTransform(make_transform(v));
  grid->setSaveFloatAsHalf(half);
  // Wrap our x-fastest buffer (no copy) and let OpenVDB's threaded copy activate every voxel
  // that differs from the background 0 (densities are >= 0, so exactly the cloud voxels).
  const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(int(v.dims[0]) - 1, int(v.dims[1]) - 1,
                                                                 int(v.dims[2]) - 1));
  openvdb::tools::Dense<const float, openvdb::tools::LayoutXYZ> dense(box, data.data());
  openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  openvdb::tools::prune(grid->tree());
  return grid;
}

/// An exception's text cut to a length that fits a terminal line (a damaged file once put a
/// 1.4 GB "grid type" into OpenVDB's message).
std::string short_what(const std::exception& e) {
  std::string w = e.what();
  if (w.size() > 300) w = w.substr(0, 297) + "...";
  return printable(w);
}

/// Walks the parts of a .vdb file that OpenVDB reads before any grid (header, file metadata,
/// grid descriptors) with every length and offset checked against the file's size. OpenVDB
/// trusts them: a truncated or damaged file made it allocate and print gigabytes.
void check_vdb_layout(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(printable(path) + ": cannot open file");
  const uint64_t size = uint64_t(in.tellg());
  in.seekg(0);
  uint64_t pos = 0;
  auto bad = [&](const std::string& what) {
    throw InputError(printable(path) + ": not a valid OpenVDB file: " + what + " (the file has " + std::to_string(size) +
                     " bytes; truncated or damaged?)");
  };
  auto read = [&](void* dst, uint64_t n, const char* what) {
    if (n > size - pos) bad(std::string(what) + " at byte " + std::to_string(pos) + " runs past the end");
    in.read(static_cast<char*>(dst), std::streamsize(n));
    if (!in) bad(std::string("cannot read ") + what);
    pos += n;
  };
  auto skip_string = [&](const char* what, uint32_t max_len) {
    uint32_t n = 0;
    read(&n, 4, what);
    if (n > max_len || n > size - pos)
      bad(std::string(what) + " at byte " + std::to_string(pos - 4) + " claims " + std::to_string(n) + " bytes");
    in.seekg(std::streamoff(pos + n));
    pos += n;
  };
  int64_t magic = 0;
  read(&magic, 8, "magic number");
  if (magic != openvdb::OPENVDB_MAGIC) bad("no OpenVDB magic number at the start");
  uint32_t version = 0, lib[2];
  read(&version, 4, "file format version");
  if (version < openvdb::OPENVDB_FILE_VERSION_BOOST_UUID) return;  // ancient layout: left to OpenVDB
  read(lib, 8, "library version");
  char has_offsets = 0;
  read(&has_offsets, 1, "grid offsets flag");
  if (version < openvdb::OPENVDB_FILE_VERSION_SELECTIVE_COMPRESSION) {
    char c;
    read(&c, 1, "compression flag");
  }
  char uuid[36];
  read(uuid, 36, "file UUID");
  uint32_t meta_count = 0;
  read(&meta_count, 4, "metadata count");
  if (meta_count > 100000) bad("it claims " + std::to_string(meta_count) + " metadata entries");
  for (uint32_t i = 0; i < meta_count; ++i) {
    skip_string("metadata name", 1 << 16);
    skip_string("metadata type", 1 << 10);
    skip_string("metadata value", 1u << 30);
  }
  if (!has_offsets) return;  // a streamed file: grids follow one another, read by OpenVDB
  int32_t grids = 0;
  read(&grids, 4, "grid count");
  if (grids < 0 || grids > 100000) bad("it claims " + std::to_string(grids) + " grids");
  for (int32_t g = 0; g < grids; ++g) {
    skip_string("grid name", 1 << 16);
    skip_string("grid type", 1 << 10);
    if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) skip_string("grid instance parent", 1 << 16);
    int64_t off[3];
    read(off, 24, "grid offsets");
    for (int k = 0; k < 3; ++k)
      if (off[k] < int64_t(pos) || uint64_t(off[k]) > size)
        bad("grid " + std::to_string(g) + " ends at byte " + std::to_string(off[2]) + ", past the end");
    if (!(off[0] <= off[1] && off[1] <= off[2])) bad("grid " + std::to_string(g) + " has inconsistent offsets");
    in.seekg(off[2]);
    pos = uint64_t(off[2]);
  }
}

/// A .vdb file read whole through io::Stream on a stream that throws on any failed read: OpenVDB
/// does not check its reads, and past the end of a damaged file it used values it never read
/// (a "compressed size" of 140 TB, found by fuzzing). io::File opens its own unchecked stream.
class VdbFile {
 public:
  explicit VdbFile(const std::string& path) : path_(path) {
    init_vdb();
    check_vdb_layout(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(printable(path) + ": cannot open file");
    in.exceptions(std::ios::failbit | std::ios::badbit);
    auto fail = [&](const std::string& why) {
      throw InputError(printable(path) + ": not a readable OpenVDB file (" + why + ")");
    };
    try {
      openvdb::io::Stream s(in, /*delayLoad=*/false);
      grids_ = s.getGrids();
      meta_ = s.getMetadata();
      compression_ = s.compression();
    } catch (const openvdb::Exception& e) {
      fail(short_what(e));
    } catch (const std::ios_base::failure&) {
      fail("it ends or breaks off in the middle of a grid");
    } catch (const std::bad_alloc&) {
      // OpenVDB sizes buffers from the file: a damaged one asks for absurd amounts.
      fail("it asks for more memory than is available: damaged, or too large for this machine");
    } catch (const std::length_error& e) {
      fail(short_what(e));
    }
    if (!grids_ || grids_->empty())
      throw InputError(printable(path) + ": the OpenVDB file holds no grids (empty, or truncated after its header)");
  }
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& g : *grids_) n.push_back(g->getName());
    return n;
  }
  /// The grid called `name` (the first, if several share it); nullptr if none.
  openvdb::GridBase::Ptr grid(const std::string& name) const {
    for (const auto& g : *grids_)
      if (g->getName() == name) return g;
    return nullptr;
  }
  const openvdb::GridPtrVec& grids() const { return *grids_; }
  const openvdb::MetaMap& metadata() const { return *meta_; }
  uint32_t compression() const { return compression_; }

 private:
  std::string path_;
  openvdb::GridPtrVecPtr grids_;
  openvdb::MetaMap::Ptr meta_;
  uint32_t compression_ = 0;
};

}  // namespace

namespace {

/// OpenVDB's io::File::write opens its own std::ofstream and never checks it, so a full disk
/// gave a truncated file and exit 0. Archive::write on our checked stream, with the same
/// `seekable` layout io::File writes, reports every failed write.
class CheckedVdbArchive : public openvdb::io::Archive {
 public:
  void write_to(std::ostream& os, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) const {
    openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
  }
};

}  // namespace

void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
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
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);
  for (auto& [k, val] : v.metadata) density->insertMeta(k, openvdb::StringMetadata(val));
  // Never a creator starting with "Houdini": Blender then assumes a Y-up Houdini file and rotates it.
  density->setCreator(std::string("cloudgen ") + CLOUDGEN_VERSION);
  CheckedVdbArchive archive;
  uint32_t comp = openvdb::io::COMPRESS_ACTIVE_MASK;
  switch (o.vdb_compression) {
    case VdbCompression::Blosc:
      comp |= openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC : openvdb::io::COMPRESS_ZIP;
      break;
    case VdbCompression::Zip: comp |= openvdb::io::COMPRESS_ZIP; break;
    case VdbCompression::None: break;
  }
  archive.setCompression(comp);
  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata(std::string("cloudgen ") + CLOUDGEN_VERSION));
  batch.stage(path, [&](const std::string& tmp) {
    write_file_stream(tmp, [&](std::ostream& os) {
      try {
        archive.write_to(os, grids, meta);
      } catch (const openvdb::Exception& e) {
        throw IoError(printable(path) + ": OpenVDB could not write the grids: " + e.what());
      }
    });
  });
}

Volume read_vdb(const std::string& path, uint64_t max_bytes) {
  const VdbFile file(path);
  openvdb::GridBase::Ptr base;
  const std::vector<std::string> names = file.names();
  if (std::find(names.begin(), names.end(), "density") == names.end()) {
    std::string have;
    for (auto& n : names) have += (have.empty() ? "" : ", ") + n;
    throw InputError(printable(path) + ": no float grid named \"density\" (grids: " + (have.empty() ? "none" : have) + ")");
  }
  base = file.grid("density");
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw InputError(printable(path) + ": grid \"density\" is " + printable(base->valueType()) + ", expected float");
  if (grid->getGridClass() == openvdb::GRID_LEVEL_SET)
    throw InputError(printable(path) + ": grid \"density\" is a level set (signed distances to a surface), not a fog "
                     "volume of densities; convert it first (e.g. OpenVDB's sdfToFogVolume, or Houdini's VDB Convert)");
  if (!grid->transform().isLinear() || !grid->hasUniformVoxels())
    throw InputError(printable(path) + ": grid \"density\" needs a linear transform with cubic voxels");
  Volume v;
  openvdb::CoordBBox bb = grid->evalActiveVoxelBoundingBox();
  if (bb.empty()) throw InputError(printable(path) + ": grid \"density\" has no active voxels");
  if (!(grid->voxelSize()[0] > 0) || !std::isfinite(grid->voxelSize()[0]) || grid->voxelSize()[0] > 1e9)
    throw InputError(printable(path) + ": voxel size " + std::to_string(grid->voxelSize()[0]) + " is outside (0, 1e9] metres");
  const openvdb::Coord lo = bb.min(), dim = bb.dim();
  uint64_t count = 0, xy = 0;
  if (__builtin_mul_overflow(uint64_t(dim.x()), uint64_t(dim.y()), &xy) ||
      __builtin_mul_overflow(xy, uint64_t(dim.z()), &count) || dim.x() > 65536 || dim.y() > 65536 || dim.z() > 65536)
    throw InputError(printable(path) + ": the active bounding box " + std::to_string(dim.x()) + " x " +
                     std::to_string(dim.y()) + " x " + std::to_string(dim.z()) + " is too large to load densely");
  int channels = 1;
  for (int c = 0; c < 3; ++c) channels += std::find(names.begin(), names.end(), v.detail_names[c]) != names.end();
  check_read_budget(count, channels, 0, max_bytes, path);
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
      if (auto d = openvdb::gridPtrCast<openvdb::FloatGrid>(file.grid(v.detail_names[c])))
        fill(*d, v.detail[c]);
  check_finite_channels(v, path);
  for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it)
    if (it->first.rfind("file_", 0) != 0 && it->first != "class" && it->first != "name")
      v.metadata.push_back({it->first, it->second->str()});
  build_occupancy(v);
  return v;
}

std::string describe_vdb(const std::string& path) {
  const VdbFile file(path);
  std::ostringstream o;
  o << printable(path) << " (OpenVDB, compression " << openvdb::io::compressionToString(file.compression()) << ")\n";
  for (auto it = file.metadata().beginMeta(); it != file.metadata().endMeta(); ++it)
    o << "  file " << printable(it->first) << ": " << printable(it->second->str()) << "\n";
  for (const openvdb::GridBase::Ptr& g : file.grids()) {
    o << "  grid \"" << printable(g->getName()) << "\": " << printable(g->valueType()) << ", class "
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
      // Finite values only in min/max; NaN and infinities counted (tiles count once per value).
      float lo = 0, hi = 0;
      size_t finite = 0, nan = 0, inf = 0;
      for (auto v = fg->cbeginValueOn(); v; ++v) {
        const float f = *v;
        if (std::isnan(f)) ++nan;
        else if (std::isinf(f)) ++inf;
        else if (finite++ == 0) lo = hi = f;
        else lo = std::min(lo, f), hi = std::max(hi, f);
      }
      if (finite) o << "    values min " << lo << ", max " << hi << ", background " << fg->background() << "\n";
      if (nan || inf)
        o << "    WARNING: " << nan << " NaN and " << inf << " infinite values (not valid densities)\n";
      if (g->getGridClass() == openvdb::GRID_LEVEL_SET)
        o << "    WARNING: a level set (signed distances), not a fog volume: cloudviewer refuses it as density\n";
    }
    for (auto m = g->beginMeta(); m != g->endMeta(); ++m)
      if (m->first.rfind("file_", 0) != 0)
        o << "    " << printable(m->first) << ": " << printable(m->second->str()) << "\n";
  }
  return o.str();
}

}  // namespace cloudgen
