// NanoVDB export and import (.nvdb): the only translation unit that includes NanoVDB's C++
// headers (and, through OpenToNanoVDB.h, OpenVDB's: 15-25 s to compile).
//
// The grids are the .vdb export's (vdb::export_grids + vdb::finish_grids: density, the dilated
// detail grids, the physical scale), each converted with nanovdb::OpenToNanoVDB into a zeroed
// buffer (NanoVDB leaves padding and the unused half of tile unions uninitialised, which would
// make the bytes differ run to run). NanoVDB grids carry name, class, transform and bounding box
// but no key/value metadata, so the density grid gets one blind-data block, "cloudgen_metadata",
// holding the .vdb export's metadata as JSON (other readers skip blind data they do not know).
//
// export.nvdb.precision writes the grids with NanoVDB's quantised leaves (Fp16, Fp8, Fp4, FpN)
// instead of float. The reader takes every one of them and decodes it to a float grid of the same
// tree on reading (through an OpenVDB tree, then the float conversion), so everything after parse_nvdb (the
// viewer's shaders, the page table, the dense copy) sees float grids only.
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridChecksum.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cloudgen/io.h"
#include "cloudgen/nvdb.h"
#include "cloudgen/schema.h"
#include "io/format_internal.h"
#include "io/vdb_internal.h"

namespace cloudgen {
namespace {
// NanoVDB's Version::c_str() returns a malloc'd buffer its callers must free (a leak on every
// damaged file's message: found by fuzz_nvdb); the text from the version's parts instead.
std::string version_text(const nanovdb::Version& v) {
  return std::to_string(v.getMajor()) + "." + std::to_string(v.getMinor()) + "." + std::to_string(v.getPatch());
}

using json = nlohmann::json;
using NanoGrid = nanovdb::NanoGrid<float>;
using NanoTree = nanovdb::NanoTree<float>;
using NanoRoot = nanovdb::NanoRoot<float>;
using NanoUpper = nanovdb::NanoUpper<float>;
using NanoLower = nanovdb::NanoLower<float>;
using NanoLeaf = nanovdb::NanoLeaf<float>;
constexpr const char* kMetaBlind = "cloudgen_metadata";
constexpr const char* kPrecisionKey = "nvdb_precision";  ///< metadata of quantised files: fp16, fp8, fp4, fpn
constexpr size_t kMaxGrids = 64;

uint64_t round32(uint64_t n) { return (n + 31) / 32 * 32; }

/// A block vector as one byte array, as NanoVolume::data() gives its buffer: offsets go from here,
/// not from `front().b` (indexing past that 32-byte member array is out of bounds).
uint8_t* bytes(std::vector<NanoVolume::Block>& v) { return reinterpret_cast<uint8_t*>(v.data()); }

void zero_inactive(NanoGrid& grid);

/// Calls f with a value of the build type of NanoVDB grid type t (float or a quantised leaf type;
/// anything else is not a cloudgen grid and returns false).
template <class F>
bool with_build_type(nanovdb::GridType t, F f) {
  switch (t) {
    case nanovdb::GridType::Float: return f(float{}), true;
    case nanovdb::GridType::Fp16: return f(nanovdb::Fp16{}), true;
    case nanovdb::GridType::Fp8: return f(nanovdb::Fp8{}), true;
    case nanovdb::GridType::Fp4: return f(nanovdb::Fp4{}), true;
    case nanovdb::GridType::FpN: return f(nanovdb::FpN{}), true;
    default: return false;
  }
}

/// The precision's name (export.nvdb.precision) of a grid type with_build_type accepts.
const char* precision_of(nanovdb::GridType t) {
  switch (t) {
    case nanovdb::GridType::Fp16: return nvdb_precision_name(NvdbPrecision::Fp16);
    case nanovdb::GridType::Fp8: return nvdb_precision_name(NvdbPrecision::Fp8);
    case nanovdb::GridType::Fp4: return nvdb_precision_name(NvdbPrecision::Fp4);
    case nanovdb::GridType::FpN: return nvdb_precision_name(NvdbPrecision::FpN);
    default: return nvdb_precision_name(NvdbPrecision::Float);
  }
}

/// One OpenVDB float grid as NanoVDB bytes of build type B (bounding box and min/max computed, no
/// checksum yet). B = float: inactive values zeroed (zero_inactive). A quantised B maps each leaf's
/// 512 values, inactive ones included, onto [min, max] of the leaf, rounding to the nearest code
/// (dithering off); FpN picks per leaf the fewest bits whose every value is within `tolerance`.
template <class B>
std::vector<NanoVolume::Block> convert_as(const openvdb::FloatGrid& g, float tolerance) {
  using Converter = nanovdb::OpenToNanoVDB<float, B, nanovdb::AbsDiff, nanovdb::HostBuffer>;
  auto converter = [tolerance] {
    Converter c;
    c.oracle().setTolerance(tolerance);  // read by FpN only
    c.enableDithering(false);
    return c;
  };
  const uint64_t size = converter()(g, nanovdb::StatsMode::All, nanovdb::ChecksumMode::Disable, 0).size();
  std::vector<NanoVolume::Block> out(round32(size) / 32 + 1);
  std::memset(out.data(), 0, out.size() * 32);
  nanovdb::HostBuffer pool = nanovdb::HostBuffer::createPool(out.size() * 32, out.data());
  auto handle = converter()(g, nanovdb::StatsMode::All, nanovdb::ChecksumMode::Disable, 0, pool);
  if (handle.size() != size || handle.data() != bytes(out))
    throw Error("NanoVDB conversion of grid \"" + g.getName() + "\" did not land in its buffer");
  out.resize(round32(size) / 32);
  if (std::is_same<B, float>::value) zero_inactive(*reinterpret_cast<NanoGrid*>(bytes(out)));
  return out;
}
std::vector<NanoVolume::Block> convert(const openvdb::FloatGrid& g) { return convert_as<float>(g, 0.0f); }

/// A checked quantised grid (build type B) decoded to a float grid of the same tree and transform.
/// Every node's origin comes from its root tile's key and its slots (not from the node, whose
/// stored origin check_tree compares for leaves only); inactive values stay 0 (zero_inactive's rule).
template <class B>
std::vector<NanoVolume::Block> decode(const std::vector<NanoVolume::Block>& q) {
  using Upper = nanovdb::NanoUpper<B>;
  using Lower = nanovdb::NanoLower<B>;
  using Leaf = nanovdb::NanoLeaf<B>;
  const auto& grid = *reinterpret_cast<const nanovdb::NanoGrid<B>*>(q.data());
  const openvdb::FloatGrid::Ptr f = openvdb::FloatGrid::create(0.0f);
  f->setName(grid.shortGridName());
  f->setGridClass(grid.gridClass() == nanovdb::GridClass::LevelSet ? openvdb::GRID_LEVEL_SET : openvdb::GRID_FOG_VOLUME);
  openvdb::FloatTree& tree = f->tree();
  auto ov = [](const nanovdb::Coord& c) { return openvdb::Coord(c[0], c[1], c[2]); };
  const auto* root = grid.tree().root().data();
  for (uint32_t i = 0; i < root->mTableSize; ++i) {
    const auto* t = root->tile(i);
    if (!t->isChild()) {
      if (t->state) tree.addTile(3, ov(t->origin()), t->value, true);
      continue;
    }
    const auto* up = root->getChild(t)->data();
    for (uint32_t n = 0; n < Upper::SIZE; ++n) {
      const nanovdb::Coord lo = t->origin() + (Upper::OffsetToLocalCoord(n) << Lower::TOTAL);
      if (!up->mChildMask.isOn(n)) {
        if (up->mValueMask.isOn(n)) tree.addTile(2, ov(lo), up->mTable[n].value, true);
        continue;
      }
      const auto* low = up->getChild(n)->data();
      for (uint32_t m = 0; m < Lower::SIZE; ++m) {
        const nanovdb::Coord lf = lo + (Lower::OffsetToLocalCoord(m) << Leaf::TOTAL);
        if (!low->mChildMask.isOn(m)) {
          if (low->mValueMask.isOn(m)) tree.addTile(1, ov(lf), low->mTable[m].value, true);
          continue;
        }
        const Leaf& leaf = *low->getChild(m);
        if (leaf.valueMask().isOff()) continue;
        openvdb::FloatTree::LeafNodeType* out = tree.touchLeaf(ov(lf));
        for (auto it = leaf.valueMask().beginOn(); it; ++it) out->setValueOn(*it, leaf.getValue(*it));
      }
    }
  }
  std::vector<NanoVolume::Block> out = convert(*f);
  // The transform as the file has it (the OpenVDB grid above has none).
  auto* to = reinterpret_cast<nanovdb::GridData*>(bytes(out));
  const auto* from = reinterpret_cast<const nanovdb::GridData*>(q.data());
  to->mMap = from->mMap;
  to->mWorldBBox = from->mWorldBBox;
  to->mVoxelSize = from->mVoxelSize;
  return out;
}

/// Appends the blind-data block holding `text` to a converted grid and updates its size.
void add_metadata_blind(std::vector<NanoVolume::Block>& buf, const std::string& text) {
  const uint64_t grid_bytes = buf.size() * 32;
  const uint64_t meta_at = grid_bytes, data_at = meta_at + sizeof(nanovdb::GridBlindMetaData);
  const uint64_t total = round32(data_at + text.size() + 1);
  buf.resize(total / 32);
  std::memset(bytes(buf) + grid_bytes, 0, total - grid_bytes);
  auto* meta = reinterpret_cast<nanovdb::GridBlindMetaData*>(bytes(buf) + meta_at);
  meta->mByteOffset = int64_t(data_at - meta_at);
  meta->mElementCount = text.size() + 1;
  meta->mFlags = 0;
  meta->mSemantic = nanovdb::GridBlindDataSemantic::Unknown;
  meta->mDataClass = nanovdb::GridBlindDataClass::Unknown;
  meta->mDataType = nanovdb::GridType::Unknown;
  std::strncpy(meta->mName, kMetaBlind, nanovdb::GridBlindMetaData::MaxNameSize - 1);
  std::memcpy(bytes(buf) + data_at, text.data(), text.size());
  auto* grid = reinterpret_cast<nanovdb::GridData*>(bytes(buf));
  grid->mBlindMetadataOffset = int64_t(meta_at);
  grid->mBlindMetadataCount = 1;
  grid->mGridSize = total;
}

std::string meta_json(const openvdb::GridBase& g) {
  json j = json::object();
  for (auto it = g.beginMeta(); it != g.endMeta(); ++it) {
    if (it->first.rfind("file_", 0) == 0 || it->first == "class" || it->first == "name") continue;
    const std::string type = it->second->typeName();
    if (auto d = g.getMetadata<openvdb::DoubleMetadata>(it->first)) j[it->first] = d->value();
    else if (auto b = g.getMetadata<openvdb::BoolMetadata>(it->first)) j[it->first] = b->value();
    else j[it->first] = it->second->str();
  }
  return j.dump();
}

NanoGrid* grid_at(NanoVolume& n, size_t g) { return reinterpret_cast<NanoGrid*>(n.data() + n.grids[g].offset); }
const NanoGrid* grid_at(const NanoVolume& n, size_t g) {
  return reinterpret_cast<const NanoGrid*>(n.data() + n.grids[g].offset);
}

/// Multiplies every stored value (leaves, tiles, background) of grid g by k.
void scale_grid(NanoVolume& n, size_t g, float k) {
  NanoTree& tree = grid_at(n, g)->tree();
  NanoRoot& root = tree.root();
  root.data()->mBackground *= k;
  for (uint32_t i = 0; i < root.data()->mTableSize; ++i)
    if (!root.data()->tile(i)->isChild()) root.data()->tile(i)->value *= k;
  auto scale_internal = [k](auto* node, uint32_t count, uint32_t size) {
    for (uint32_t c = 0; c < count; ++c)
      for (uint32_t i = 0; i < size; ++i)
        if (!node[c].data()->mChildMask.isOn(i)) node[c].data()->mTable[i].value *= k;
  };
  if (tree.nodeCount(2)) scale_internal(tree.template getFirstNode<2>(), tree.nodeCount(2), NanoUpper::SIZE);
  if (tree.nodeCount(1)) scale_internal(tree.template getFirstNode<1>(), tree.nodeCount(1), NanoLower::SIZE);
  NanoLeaf* leaf = tree.nodeCount(0) ? tree.template getFirstNode<0>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(0); ++c)
    for (float& v : leaf[c].data()->mValues) v *= k;
}

/// Inactive values and the background to 0, so that what a lookup returns anywhere (a leaf's
/// stored value, a tile's, the background) is what the dense reader puts there (it fills active
/// values only). OpenVDB keeps stale values in voxels its topology operations turned off.
void zero_inactive(NanoGrid& grid) {
  NanoTree& tree = grid.tree();
  NanoRoot& root = tree.root();
  root.data()->mBackground = 0.0f;
  for (uint32_t i = 0; i < root.data()->mTableSize; ++i) {
    auto* t = root.data()->tile(i);
    if (!t->isChild() && !t->state) t->value = 0.0f;
  }
  auto internal = [](auto* node, uint32_t count, uint32_t size) {
    for (uint32_t c = 0; c < count; ++c)
      for (uint32_t i = 0; i < size; ++i)
        if (!node[c].data()->mChildMask.isOn(i) && !node[c].data()->mValueMask.isOn(i)) {
          node[c].data()->mTable[i].child = 0;  // the whole union: no stale half
          node[c].data()->mTable[i].value = 0.0f;
        }
  };
  if (tree.nodeCount(2)) internal(tree.template getFirstNode<2>(), tree.nodeCount(2), NanoUpper::SIZE);
  if (tree.nodeCount(1)) internal(tree.template getFirstNode<1>(), tree.nodeCount(1), NanoLower::SIZE);
  NanoLeaf* leaf = tree.nodeCount(0) ? tree.template getFirstNode<0>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(0); ++c)
    for (uint32_t i = 0; i < NanoLeaf::SIZE; ++i)
      if (!leaf[c].data()->mValueMask.isOn(i)) leaf[c].data()->mValues[i] = 0.0f;
}

/// Fills the volume-level fields of n from its density grid and the metadata block.
void describe(NanoVolume& n, const std::string& name) {
  const NanoGrid& d = *grid_at(n, 0);
  const nanovdb::CoordBBox bb = d.tree().bbox();
  if (d.tree().isEmpty() || bb.empty() || d.activeVoxelCount() == 0)
    throw InputError(printable(name) + ": grid \"density\" has no active voxels");
  for (int a = 0; a < 3; ++a) {
    const int64_t dim = int64_t(bb.max()[a]) - bb.min()[a] + 1;
    if (dim > int64_t(detail::kMaxEdge))
      throw InputError(printable(name) + ": the active bounding box is " + std::to_string(dim) + " voxels along axis " +
                       std::to_string(a) + ", more than the " + std::to_string(detail::kMaxEdge) + " allowed");
    n.dims[size_t(a)] = uint32_t(dim);
    n.index_min[size_t(a)] = bb.min()[a];
  }
  // The transform: cubic voxels, y-up or +90 degrees about x (export.vdb.up = z), as read_vdb.
  const nanovdb::Vec3d o = d.indexToWorld(nanovdb::Vec3d(0.0));
  const double vs = d.voxelSize()[0];
  if (!(vs > 0) || !std::isfinite(vs) || vs > 1e9 || std::abs(d.voxelSize()[1] - vs) > 1e-9 * vs ||
      std::abs(d.voxelSize()[2] - vs) > 1e-9 * vs)
    throw InputError(printable(name) + ": grid \"density\" needs cubic voxels of a size in (0, 1e9] metres");
  auto axis = [&](int a) {
    nanovdb::Vec3d e(0.0);
    e[a] = 1;
    return (d.indexToWorld(e) - o) / vs;
  };
  auto near = [](const nanovdb::Vec3d& a, double x, double y, double z) {
    return std::abs(a[0] - x) + std::abs(a[1] - y) + std::abs(a[2] - z) < 1e-6;
  };
  const nanovdb::Vec3d x = axis(0), y = axis(1), z = axis(2);
  if (near(x, 1, 0, 0) && near(y, 0, 1, 0) && near(z, 0, 0, 1)) n.up = 'y';
  else if (near(x, 1, 0, 0) && near(y, 0, 0, 1) && near(z, 0, -1, 0)) n.up = 'z';
  else
    throw InputError(printable(name) + ": grid \"density\" has a rotated or sheared transform; cloudgen reads "
                     "axis-aligned y-up grids and y-up grids turned +90 degrees about x (export.vdb.up = z)");
  nanovdb::Vec3d w = d.indexToWorld(nanovdb::Vec3d(bb.min()[0], bb.min()[1], bb.min()[2]));
  if (n.up == 'z') w = nanovdb::Vec3d(w[0], w[2], -w[1]);
  n.voxel_size = vs;
  for (int a = 0; a < 3; ++a) {
    n.origin[size_t(a)] = w[a] - 0.5 * vs;
    if (!std::isfinite(n.origin[size_t(a)]) || std::abs(n.origin[size_t(a)]) > 1e12)
      throw InputError(printable(name) + ": grid \"density\" has a non-finite or absurd origin");
  }
  Volume names;
  for (size_t g = 1; g < n.grids.size(); ++g)
    for (int c = 0; c < 3; ++c)
      if (n.grids[g].name == names.detail_names[size_t(c)] && n.detail[size_t(c)] < 0) n.detail[size_t(c)] = int(g);
}

/// The metadata block's keys into n (normalising physical densities like read_vdb).
void apply_metadata(NanoVolume& n, const std::string& text, const std::string& name) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception&) {
    throw InputError(printable(name) + ": the \"" + kMetaBlind + "\" block of grid \"density\" is not JSON");
  }
  if (!j.is_object()) throw InputError(printable(name) + ": the \"" + kMetaBlind + "\" block is not a JSON object");
  const auto& computed = vdb::computed_meta();
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (computed.count(it.key())) continue;
    n.metadata.push_back({it.key(), it->is_string() ? it->get<std::string>() : it->dump()});
  }
  if (j.contains("tiles_xz") && j["tiles_xz"].is_boolean()) n.tiles_xz = j["tiles_xz"].get<bool>();
  if (j.contains("density_units") && j["density_units"] == "extinction_per_metre") {
    const double ext = j.contains("extinction_per_metre") && j["extinction_per_metre"].is_number()
                           ? j["extinction_per_metre"].get<double>()
                           : 0.0;
    if (!(ext > 0) || !std::isfinite(ext))
      throw InputError(printable(name) + ": density_units is extinction_per_metre but extinction_per_metre is missing "
                       "or not positive");
    for (size_t g = 0; g < 1; ++g) scale_grid(n, g, float(1.0 / ext));
  }
}

/// Whether grids a and b have the same node layout: the same tree counts and offsets, root
/// table, child links and leaf origins (values may differ), so equal offsets address equal voxels.
bool same_layout(const NanoVolume& n, size_t a, size_t b) {
  const NanoGrid& ga = *grid_at(n, a);
  const NanoGrid& gb = *grid_at(n, b);
  const auto* ta = reinterpret_cast<const nanovdb::TreeData<3>*>(&ga.tree());
  const auto* tb = reinterpret_cast<const nanovdb::TreeData<3>*>(&gb.tree());
  for (int i = 0; i < 4; ++i)
    if (ta->mNodeOffset[i] != tb->mNodeOffset[i]) return false;
  for (int i = 0; i < 3; ++i)
    if (ta->mNodeCount[i] != tb->mNodeCount[i]) return false;
  const auto* ra = ga.tree().root().data();
  const auto* rb = gb.tree().root().data();
  if (ra->mTableSize != rb->mTableSize) return false;
  for (uint32_t i = 0; i < ra->mTableSize; ++i)
    if (!(ra->tile(i)->key == rb->tile(i)->key) || ra->tile(i)->child != rb->tile(i)->child) return false;
  auto internal = [&](auto* na, auto* nb, uint32_t count) {
    for (uint32_t c = 0; c < count; ++c) {
      if (!(na[c].data()->mChildMask == nb[c].data()->mChildMask)) return false;
      for (auto it = na[c].data()->mChildMask.beginOn(); it; ++it)
        if (na[c].data()->mTable[*it].child != nb[c].data()->mTable[*it].child) return false;
    }
    return true;
  };
  const auto& xa = ga.tree();
  const auto& xb = gb.tree();
  if (xa.nodeCount(2) && !internal(xa.template getFirstNode<2>(), xb.template getFirstNode<2>(), xa.nodeCount(2))) return false;
  if (xa.nodeCount(1) && !internal(xa.template getFirstNode<1>(), xb.template getFirstNode<1>(), xa.nodeCount(1))) return false;
  const NanoLeaf* la = xa.nodeCount(0) ? xa.template getFirstNode<0>() : nullptr;
  const NanoLeaf* lb = xb.nodeCount(0) ? xb.template getFirstNode<0>() : nullptr;
  for (uint32_t c = 0; c < xa.nodeCount(0); ++c)
    if (!(la[c].origin() == lb[c].origin())) return false;
  return true;
}

/// Active voxels of a grid, each active tile counted as the voxels it covers: 4096^3 for a root
/// tile, 128^3 and 8^3 for the internal nodes'. NanoVDB's own count (OpenToNanoVDB's mVoxelCount)
/// takes a root tile for 32^3 voxels, and a file's is whatever the file says: a 17 KB file of one
/// 65536^3 active region counted as a few thousand voxels, and the viewer set to work on it as on
/// a small cloud (issue 47). Saturates instead of wrapping (a damaged file can claim anything).
uint64_t active_voxels_with_tiles(const NanoGrid& grid) {
  const NanoTree& tree = grid.tree();
  uint64_t n = 0;
  auto add = [&](uint64_t count, uint64_t each) {
    const uint64_t k = count > UINT64_MAX / each ? UINT64_MAX : count * each;
    n = n > UINT64_MAX - k ? UINT64_MAX : n + k;
  };
  const auto* root = tree.root().data();
  uint64_t root_tiles = 0;
  for (uint32_t i = 0; i < root->mTableSize; ++i) root_tiles += !root->tile(i)->isChild() && root->tile(i)->state;
  add(root_tiles, uint64_t(NanoUpper::DIM) * NanoUpper::DIM * NanoUpper::DIM);
  auto tiles = [](const auto& data) {  // value-mask bits that are not children: the active tiles
    uint64_t t = 0;
    for (auto it = data.mValueMask.beginOn(); it; ++it) t += !data.mChildMask.isOn(*it);
    return t;
  };
  const NanoUpper* up = tree.nodeCount(2) ? tree.template getFirstNode<2>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(2); ++c) add(tiles(*up[c].data()), uint64_t(NanoLower::DIM) * NanoLower::DIM * NanoLower::DIM);
  const NanoLower* low = tree.nodeCount(1) ? tree.template getFirstNode<1>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(1); ++c) add(tiles(*low[c].data()), uint64_t(NanoLeaf::DIM) * NanoLeaf::DIM * NanoLeaf::DIM);
  const NanoLeaf* leaf = tree.nodeCount(0) ? tree.template getFirstNode<0>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(0); ++c) add(leaf[c].valueMask().countOn(), 1);
  return n;
}

NanoVolume assemble(std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> parts, const std::string& name) {
  NanoVolume n;
  uint64_t total = 0;
  for (auto& p : parts) total += p.second.size();
  n.buffer.reserve(total);
  for (auto& [gname, bytes] : parts) {
    NanoVolume::Grid g;
    g.name = gname;
    g.offset = n.buffer.size() * 32;
    g.bytes = bytes.size() * 32;
    n.buffer.insert(n.buffer.end(), bytes.begin(), bytes.end());
    n.grids.push_back(g);
  }
  for (size_t i = 0; i < n.grids.size(); ++i) {
    const NanoGrid& g = *grid_at(n, i);
    n.grids[i].active_voxels = active_voxels_with_tiles(g);
    for (int l = 0; l < 3; ++l) (l == 0 ? n.grids[i].leaves : l == 1 ? n.grids[i].lower : n.grids[i].upper) = g.tree().nodeCount(l);
  }
  describe(n, name);
  n.detail_shared_layout = n.has_detail() && same_layout(n, size_t(n.detail[0]), size_t(n.detail[1])) &&
                           same_layout(n, size_t(n.detail[0]), size_t(n.detail[2]));
  return n;
}

/// The grids of the .vdb export as NanoVDB bytes of build type B, density first, with metadata and
/// checksums.
template <class B = float>
std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> nano_grids(const openvdb::GridPtrVec& grids,
                                                                               float tolerance = 0.0f) {
  std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> out;
  for (size_t i = 0; i < grids.size(); ++i) {
    auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[i]);
    if (!g) continue;  // only float grids: the viewer's channels
    std::vector<NanoVolume::Block> b = convert_as<B>(*g, tolerance);
    if (i == 0) add_metadata_blind(b, meta_json(*g));
    nanovdb::updateChecksum(*reinterpret_cast<nanovdb::NanoGrid<B>*>(bytes(b)), nanovdb::ChecksumMode::Full);
    out.push_back({g->getName(), std::move(b)});
  }
  return out;
}

/// Inactive voxels of every leaf to 0 before quantising, as the float export stores them: a stale
/// value OpenVDB left in a voxel it turned off would widen its leaf's [min, max] and so its step.
void zero_inactive_leaf_values(const openvdb::GridPtrVec& grids) {
  for (const auto& base : grids)
    if (auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(base))
      for (auto leaf = g->tree().beginLeaf(); leaf; ++leaf)
        for (auto it = leaf->beginValueOff(); it; ++it) it.setValue(0.0f);
}

NanoVolume nano_of_export(const Volume& v, const std::string& path, const ExportOptions& o) {
  double erosion = 0;
  const openvdb::GridPtrVec grids = vdb::export_grids(v, path, o, &erosion);
  vdb::finish_grids(v, grids, path, o, erosion);
  NanoVolume n = assemble(nano_grids(grids), path);
  // The metadata block describes the file; in memory the values are normalised like read_nvdb's.
  apply_metadata(n, meta_json(*grids[0]), path);
  return n;
}

/// The .nvdb file of NanoVDB grids (any build type with_build_type takes): the layout
/// nanovdb::io::writeGrids writes uncompressed.
std::string nvdb_file_bytes(const std::vector<std::pair<std::string, const uint8_t*>>& grids) {
  nanovdb::io::Segment seg(nanovdb::io::Codec::NONE);
  for (const auto& grid : grids) {
    const uint8_t* p = grid.second;  // not a structured binding: clang 14 cannot capture one
    const std::string& name = grid.first;
    const auto* gd = reinterpret_cast<const nanovdb::GridData*>(p);
    const bool known = with_build_type(gd->mGridType, [&](auto tag) {
      using B = decltype(tag);
      nanovdb::io::GridMetaData m(gd->mGridSize, nanovdb::io::Codec::NONE,
                                  *reinterpret_cast<const nanovdb::NanoGrid<B>*>(p));
      m.fileSize = gd->mGridSize;
      seg.meta.push_back(m);
    });
    if (!known) throw Error("grid \"" + name + "\" has a value type the .nvdb writer does not write");
    seg.header.gridCount += 1;
  }
  std::ostringstream os;
  seg.write(os);
  for (const auto& g : grids)
    os.write(reinterpret_cast<const char*>(g.second),
             std::streamsize(reinterpret_cast<const nanovdb::GridData*>(g.second)->mGridSize));
  if (!os) throw Error("could not assemble the NanoVDB file in memory");
  return os.str();
}
std::string nvdb_file_bytes(const NanoVolume& n) {
  std::vector<std::pair<std::string, const uint8_t*>> grids;
  for (const auto& g : n.grids) grids.push_back({g.name, n.data() + g.offset});
  return nvdb_file_bytes(grids);
}

// ---------------------------------------------------------------------------------------------
// Checked reading: every offset the tree walk would follow lies inside the grid, on a node of
// the right level, before anything dereferences it.

struct Checker {
  const uint8_t* base;  // the grid
  uint64_t size;
  std::string where;
  [[noreturn]] void bad(const std::string& what) const {
    throw InputError(where + ": not a valid NanoVDB grid: " + what + " (truncated or damaged?)");
  }
  /// The node array of a level: [first, first + count * node_size) inside the grid.
  void array(uint64_t first, uint64_t count, uint64_t node_size, const char* what) const {
    if (count == 0) return;
    if (first % 32 || first >= size || count > (size - first) / node_size)
      bad(std::string(what) + " nodes lie outside the grid");
  }
  /// A child link from `from` (byte offset in the grid) must land on a node of the child array.
  void link(uint64_t from, int64_t off, uint64_t first, uint64_t count, uint64_t node_size, const char* what) const {
    const int64_t at = int64_t(from) + off;
    if (at < int64_t(first) || uint64_t(at) >= first + count * node_size || (uint64_t(at) - first) % node_size)
      bad(std::string("a link to a ") + what + " node points outside its array");
  }
};

/// The tree of a grid of build type B: node arrays, child links and node counts. FpN leaves vary
/// in size (a 96-byte header, then 64 bytes per bit of its width, 1 to 16), so a link to one is
/// checked for the leaf's own extent rather than for a place in an array of equal nodes.
template <class B>
void check_tree(const uint8_t* p, uint64_t size, const Checker& c) {
  using Upper = nanovdb::NanoUpper<B>;
  using Lower = nanovdb::NanoLower<B>;
  using Leaf = nanovdb::NanoLeaf<B>;
  constexpr bool fixed_leaves = Leaf::DataType::FIXED_SIZE;
  const uint64_t tree_at = sizeof(nanovdb::GridData);
  const auto* td = reinterpret_cast<const nanovdb::TreeData<3>*>(p + tree_at);
  const uint64_t root_at = tree_at + td->mNodeOffset[3];
  if (td->mNodeOffset[3] > size || root_at % 32 || root_at + sizeof(nanovdb::RootData<Upper>) > size)
    c.bad("the root node lies outside the grid");
  const auto* root = reinterpret_cast<const nanovdb::RootData<Upper>*>(p + root_at);
  const uint64_t tiles = root->mTableSize;
  using Tile = typename nanovdb::RootData<Upper>::Tile;
  if (tiles > (size - root_at - sizeof(*root)) / sizeof(Tile)) c.bad("the root table runs past the end");
  const uint64_t counts[3] = {td->mNodeCount[0], td->mNodeCount[1], td->mNodeCount[2]};
  uint64_t first[3];
  // An FpN leaf is at least its header and one bit a voxel.
  const uint64_t node_size[3] = {fixed_leaves ? sizeof(Leaf) : sizeof(Leaf) + 64, sizeof(Lower), sizeof(Upper)};
  const char* names[3] = {"leaf", "lower internal", "upper internal"};
  for (int l = 0; l < 3; ++l) {
    if (counts[l] && td->mNodeOffset[l] > size) c.bad(std::string(names[l]) + " nodes lie outside the grid");
    first[l] = tree_at + td->mNodeOffset[l];
    c.array(first[l], counts[l], node_size[l], names[l]);
  }
  for (uint64_t i = 0; i < tiles; ++i) {
    const Tile* t = reinterpret_cast<const Tile*>(p + root_at + sizeof(*root)) + i;
    if (t->child) c.link(root_at, t->child, first[2], counts[2], node_size[2], names[2]);
  }
  auto leaf_link = [&](uint64_t from, int64_t off) {
    if (fixed_leaves) return c.link(from, off, first[0], counts[0], node_size[0], names[0]);
    const int64_t at = int64_t(from) + off;
    if (at < int64_t(first[0]) || uint64_t(at) % 32 || uint64_t(at) > size || size - uint64_t(at) < sizeof(Leaf))
      c.bad("a link to a leaf node points outside the grid");
    const uint32_t log2_bits = reinterpret_cast<const Leaf*>(p + at)->data()->mFlags >> 5;
    if (log2_bits > 4) c.bad("a leaf claims " + std::to_string(1u << log2_bits) + " bits a value (FpN has 1 to 16)");
    if (size - uint64_t(at) - sizeof(Leaf) < (uint64_t(64) << log2_bits)) c.bad("a leaf's values run past the end");
  };
  auto internal = [&](auto* type_tag, int level) {
    using Node = std::remove_pointer_t<decltype(type_tag)>;
    for (uint64_t i = 0; i < counts[level]; ++i) {
      const uint64_t at = first[level] + i * node_size[level];
      const auto* node = reinterpret_cast<const Node*>(p + at);
      for (auto it = node->data()->mChildMask.beginOn(); it; ++it) {
        if (level == 1) leaf_link(at, node->data()->mTable[*it].child);
        else c.link(at, node->data()->mTable[*it].child, first[level - 1], counts[level - 1], node_size[level - 1],
                    names[level - 1]);
      }
    }
  };
  internal(static_cast<const Upper*>(nullptr), 2);
  internal(static_cast<const Lower*>(nullptr), 1);
  // The nodes reached from the root, level by level, number what the tree says: NanoVDB's node
  // manager (the checksum's, the decoder's walks) fills arrays of nodeCount entries by this walk.
  uint64_t reached[3] = {0, 0, 0};
  auto reach = [&](int level, uint64_t n) {
    reached[level] += n;
    if (reached[level] > counts[level]) c.bad(std::string("more ") + names[level] + " nodes are linked than the tree counts");
  };
  // On the way, every leaf's own origin must be the one its slots give (from the root tile's key
  // down): the decoder and OpenVDB go by it. Internal nodes are not compared: theirs is the
  // minimum of their active values' box, unset when they have none.
  for (uint64_t i = 0; i < tiles; ++i) {
    const Tile* t = reinterpret_cast<const Tile*>(p + root_at + sizeof(*root)) + i;
    if (!t->child) continue;
    reach(2, 1);
    const auto* up = reinterpret_cast<const Upper*>(p + root_at + t->child);
    for (auto it = up->data()->mChildMask.beginOn(); it; ++it) {
      reach(1, 1);
      const auto* low = reinterpret_cast<const Lower*>(reinterpret_cast<const uint8_t*>(up) + up->data()->mTable[*it].child);
      reach(0, low->data()->mChildMask.countOn());
      const nanovdb::Coord low_origin = t->origin() + (Upper::OffsetToLocalCoord(*it) << Lower::TOTAL);
      for (auto jt = low->data()->mChildMask.beginOn(); jt; ++jt) {
        const auto* leaf = reinterpret_cast<const Leaf*>(reinterpret_cast<const uint8_t*>(low) + low->data()->mTable[*jt].child);
        if (!(leaf->origin() == low_origin + (Lower::OffsetToLocalCoord(*jt) << Leaf::TOTAL)))
          c.bad("a leaf's origin is not where its parent puts it");
      }
    }
  }
  for (int l = 0; l < 3; ++l)
    if (reached[l] != counts[l]) c.bad(std::string("fewer ") + names[l] + " nodes are linked than the tree counts");
}

void check_grid(const uint8_t* p, uint64_t size, const std::string& where) {
  Checker c{p, size, where};
  if (size < sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>)) c.bad("it is shorter than a grid header");
  const auto* gd = reinterpret_cast<const nanovdb::GridData*>(p);
  if (gd->mMagic != NANOVDB_MAGIC_NUMBER) c.bad("no NanoVDB magic number at the start of the grid");
  if (gd->mVersion.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
    c.bad("grid version " + version_text(gd->mVersion) + ", this reader reads major version " +
          std::to_string(NANOVDB_MAJOR_VERSION_NUMBER));
  if (gd->mGridSize != size) c.bad("the grid says it has " + std::to_string(gd->mGridSize) + " bytes, the file " + std::to_string(size));
  if (gd->mGridName[nanovdb::GridData::MaxNameSize - 1] != '\0') c.bad("the grid name is not terminated");
  const bool known = with_build_type(gd->mGridType, [&](auto tag) { check_tree<decltype(tag)>(p, size, c); });
  if (!known)
    throw InputError(where + ": grid \"" + printable(gd->mGridName) + "\" has value type " +
                     (uint32_t(gd->mGridType) < uint32_t(nanovdb::GridType::End)
                          ? std::string(nanovdb::toStr(gd->mGridType))
                          : "code " + std::to_string(uint32_t(gd->mGridType)) + " (unknown)") +
                     "; cloudgen reads float grids and NanoVDB's quantised Fp4, Fp8, Fp16 and FpN");
  if (gd->mBlindMetadataCount) {
    if (gd->mBlindMetadataCount > 1024 || gd->mBlindMetadataOffset < 0 || uint64_t(gd->mBlindMetadataOffset) > size ||
        gd->mBlindMetadataCount > (size - uint64_t(gd->mBlindMetadataOffset)) / sizeof(nanovdb::GridBlindMetaData))
      c.bad("its blind data table lies outside the grid");
  }
  if (gd->mChecksum != ~uint64_t(0)) {
    const bool partial = (gd->mChecksum >> 32) == 0xFFFFFFFFu;
    with_build_type(gd->mGridType, [&](auto tag) {
      const auto* grid = reinterpret_cast<const nanovdb::NanoGrid<decltype(tag)>*>(p);
      if (!nanovdb::validateChecksum(*grid, partial ? nanovdb::ChecksumMode::Partial : nanovdb::ChecksumMode::Full))
        c.bad("its checksum does not match its contents");
    });
  }
}

/// The text of the density grid's metadata block; empty if it has none.
std::string blind_text(const nanovdb::GridData& g, uint64_t size, const std::string& where) {
  const auto* gd = &g;
  for (uint32_t i = 0; i < gd->mBlindMetadataCount; ++i) {
    const auto& m = *gd->blindMetaData(i);
    if (m.mName[nanovdb::GridBlindMetaData::MaxNameSize - 1] != '\0' || std::string(m.mName) != kMetaBlind) continue;
    const uint64_t meta_at = uint64_t(gd->mBlindMetadataOffset) + i * sizeof(nanovdb::GridBlindMetaData);
    const int64_t at = int64_t(meta_at) + m.mByteOffset;
    if (at < 0 || uint64_t(at) > size || m.mElementCount > size - uint64_t(at) || m.mElementCount == 0)
      throw InputError(where + ": the \"" + kMetaBlind + "\" block lies outside the grid");
    const char* s = reinterpret_cast<const char*>(&g) + at;
    return std::string(s, strnlen(s, size_t(m.mElementCount)));
  }
  return {};
}

}  // namespace

NanoVolume nano_from_volume(const Volume& v, const ExportOptions& o) { return nano_of_export(v, "volume", o); }

void write_nvdb(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
  double erosion = 0;
  const openvdb::GridPtrVec grids = vdb::export_grids(v, path, o, &erosion);
  vdb::finish_grids(v, grids, path, o, erosion);
  const NanoVolume n = assemble(nano_grids(grids), path);  // the float grids: checked as every .nvdb
  std::string file;
  if (o.nvdb_precision == NvdbPrecision::Float) {
    file = nvdb_file_bytes(n);  // no precision key: float files stay byte for byte what they were
  } else {
    // The preset table refuses these already; ExportOptions filled by code pass here too.
    if (o.nvdb_precision == NvdbPrecision::FpN && !(o.nvdb_tolerance >= 1e-6 && o.nvdb_tolerance <= 1000))
      throw InputError("/export/nvdb/tolerance: " + shortest_text(o.nvdb_tolerance) +
                       " is out of range; allowed: number in [1e-06, 1000] (fpn's largest error per voxel)");
    grids[0]->insertMeta(kPrecisionKey, openvdb::StringMetadata(nvdb_precision_name(o.nvdb_precision)));
    if (o.nvdb_precision == NvdbPrecision::FpN)
      grids[0]->insertMeta("nvdb_tolerance", openvdb::DoubleMetadata(o.nvdb_tolerance));
    zero_inactive_leaf_values(grids);
    const float tol = float(o.nvdb_tolerance);
    std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> parts;
    switch (o.nvdb_precision) {
      case NvdbPrecision::Fp16: parts = nano_grids<nanovdb::Fp16>(grids); break;
      case NvdbPrecision::Fp8: parts = nano_grids<nanovdb::Fp8>(grids); break;
      case NvdbPrecision::Fp4: parts = nano_grids<nanovdb::Fp4>(grids); break;
      default: parts = nano_grids<nanovdb::FpN>(grids, tol); break;
    }
    std::vector<std::pair<std::string, const uint8_t*>> view;
    for (auto& [gname, b] : parts) view.push_back({gname, bytes(b)});
    file = nvdb_file_bytes(view);
  }
  batch.stage(path, [&](const std::string& tmp) { write_file_bytes(tmp, file.data(), file.size()); });
}

NanoVolume nano_from_vdb(const std::string& path) {
  const openvdb::GridPtrVec grids = vdb::read_grids(path);
  openvdb::GridPtrVec use;
  for (const auto& g : grids)
    if (g->getName() == "density") use.push_back(g);
  if (use.empty()) throw InputError(printable(path) + ": no float grid named \"density\"");
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(use[0]);
  if (!density) throw InputError(printable(path) + ": grid \"density\" is " + printable(use[0]->valueType()) + ", expected float");
  if (density->getGridClass() == openvdb::GRID_LEVEL_SET)
    throw InputError(printable(path) + ": grid \"density\" is a level set (signed distances to a surface), not a fog "
                     "volume of densities; convert it first (e.g. OpenVDB's sdfToFogVolume)");
  if (!vdb::cubic_voxels(*density))
    throw InputError(printable(path) + ": grid \"density\" needs a linear transform with cubic voxels");
  Volume names;
  for (const std::string& d : names.detail_names)
    for (const auto& g : grids)
      if (g->getName() == d && openvdb::gridPtrCast<openvdb::FloatGrid>(g)) {
        use.push_back(g);
        break;
      }
  // The file's metadata travels as the .nvdb export's block does (then read like read_nvdb's).
  std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> parts;
  for (size_t i = 0; i < use.size(); ++i)
    parts.push_back({use[i]->getName(), convert(*openvdb::gridPtrCast<openvdb::FloatGrid>(use[i]))});
  NanoVolume n = assemble(std::move(parts), path);
  apply_metadata(n, meta_json(*density), path);
  return n;
}

NanoVolume parse_nvdb(const uint8_t* data, size_t size, const std::string& name_in) {
  const std::string name = printable(name_in);
  auto bad = [&](const std::string& what) -> void {
    throw InputError(name + ": not a valid NanoVDB file: " + what + " (the file has " + std::to_string(size) +
                     " bytes; truncated or damaged?)");
  };
  uint64_t pos = 0;
  auto take = [&](void* dst, uint64_t n, const char* what) {
    if (n > size - pos) bad(std::string(what) + " at byte " + std::to_string(pos) + " runs past the end");
    std::memcpy(dst, data + pos, size_t(n));
    pos += n;
  };
  nanovdb::io::Header h;
  take(&h, sizeof h, "the file header");
  if (h.magic == nanovdb::io::reverseEndianness(NANOVDB_MAGIC_NUMBER)) bad("it has the other byte order");
  if (h.magic != NANOVDB_MAGIC_NUMBER) bad("no NanoVDB magic number at the start");
  if (h.version.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
    bad("file version " + version_text(h.version) + ", this reader reads major version " +
        std::to_string(NANOVDB_MAJOR_VERSION_NUMBER));
  if (h.codec != nanovdb::io::Codec::NONE) {
    // Not nanovdb::io::toStr: it indexes its table with the file's value (any 16 bits; found by fuzzing).
    const auto c = static_cast<uint16_t>(h.codec);
    const std::string codec = c == 1 ? "ZIP" : c == 2 ? "BLOSC" : "unknown codec " + std::to_string(c);
    throw InputError(name + ": the NanoVDB file is compressed (" + codec +
                     "); cloudgen reads uncompressed .nvdb (nanovdb_convert without -z/-b, or cloudgen's own)");
  }
  if (h.gridCount == 0 || h.gridCount > kMaxGrids)
    bad("it claims " + std::to_string(h.gridCount) + " grids (allowed: 1 to " + std::to_string(kMaxGrids) + ")");
  std::vector<std::pair<nanovdb::io::MetaData, std::string>> metas(h.gridCount);
  for (auto& [m, gname] : metas) {
    take(&m, sizeof m, "a grid descriptor");
    if (m.nameSize == 0 || m.nameSize > nanovdb::GridData::MaxNameSize) bad("a grid name of " + std::to_string(m.nameSize) + " bytes");
    std::string s(m.nameSize, '\0');
    take(s.data(), m.nameSize, "a grid name");
    gname.assign(s.c_str());
    if (m.codec != nanovdb::io::Codec::NONE || m.fileSize != m.gridSize)
      bad("grid \"" + printable(gname) + "\" is stored compressed or with inconsistent sizes");
    if (m.gridSize % 32) bad("grid \"" + printable(gname) + "\" has a size that is not a multiple of 32 bytes");
  }
  std::vector<std::pair<std::string, std::vector<NanoVolume::Block>>> parts;
  std::vector<std::string> precisions;
  int density = -1;
  std::string density_meta;  // a quantised density's metadata block (its decoded copy has none)
  for (auto& [m, gname] : metas) {
    if (m.gridSize > size - pos)
      bad("grid \"" + printable(gname) + "\" (" + std::to_string(m.gridSize) + " bytes at byte " + std::to_string(pos) +
          ") runs past the end");
    std::vector<NanoVolume::Block> b(size_t(m.gridSize / 32));
    take(b.data(), m.gridSize, "a grid");
    const std::string where = name + ": grid \"" + printable(gname) + "\"";
    check_grid(bytes(b), m.gridSize, where);
    const nanovdb::GridType type = reinterpret_cast<const nanovdb::GridData*>(bytes(b))->mGridType;
    const bool is_density = gname == "density" && density < 0;
    if (type != nanovdb::GridType::Float) {
      if (is_density) density_meta = blind_text(*reinterpret_cast<const nanovdb::GridData*>(bytes(b)), m.gridSize, name);
      with_build_type(type, [&](auto tag) { b = decode<decltype(tag)>(b); });
    }
    zero_inactive(*reinterpret_cast<NanoGrid*>(bytes(b)));
    if (is_density) density = int(parts.size());
    parts.push_back({gname, std::move(b)});
    precisions.push_back(precision_of(type));
  }
  if (density < 0) {
    std::string have;
    for (auto& p : parts) have += (have.empty() ? "" : ", ") + printable(p.first);
    throw InputError(name + ": no float grid named \"density\" (grids: " + have + ")");
  }
  std::rotate(parts.begin(), parts.begin() + density, parts.begin() + density + 1);
  std::rotate(precisions.begin(), precisions.begin() + density, precisions.begin() + density + 1);
  NanoVolume n = assemble(std::move(parts), name);
  for (size_t g = 0; g < n.grids.size(); ++g) n.grids[g].precision = precisions[g];
  const NanoGrid& d = *grid_at(n, 0);
  if (d.gridClass() == nanovdb::GridClass::LevelSet)
    throw InputError(name + ": grid \"density\" is a level set (signed distances to a surface), not a fog volume");
  apply_metadata(n, [&] {
    const std::string t = precisions[0] != "float" ? density_meta : blind_text(*d.data(), n.grids[0].bytes, name);
    return t.empty() ? std::string("{}") : t;
  }(), name);
  // A quantised file from another writer: say so where cloudgen's own would (`cloudgen info`).
  if (precisions[0] != "float" &&
      std::none_of(n.metadata.begin(), n.metadata.end(), [](const auto& kv) { return kv.first == kPrecisionKey; }))
    n.metadata.push_back({kPrecisionKey, precisions[0]});
  return n;
}

NanoVolume read_nvdb(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file_bytes(path, size_t(1) << 40);
  return parse_nvdb(bytes.data(), bytes.size(), path);
}

Volume read_nvdb_volume(const std::string& path, uint64_t max_bytes) {
  return dense_from_nano(read_nvdb(path), max_bytes, path);
}

namespace {

/// Visits every stored value region of grid g inside the volume's box: f(lo, hi, value) for
/// tiles (hi exclusive, volume voxel coordinates) and f per voxel of each leaf.
template <class F>
void visit_values(const NanoVolume& n, size_t g, F f) {
  const NanoTree& tree = grid_at(n, g)->tree();
  const NanoRoot& root = tree.root();
  const std::array<int32_t, 3> lo = n.index_min;
  auto box = [&](const nanovdb::Coord& origin, int32_t dim, float value) {
    std::array<int64_t, 3> a{}, b{};
    for (int k = 0; k < 3; ++k) {
      a[size_t(k)] = std::max<int64_t>(0, int64_t(origin[k]) - lo[size_t(k)]);
      b[size_t(k)] = std::min<int64_t>(n.dims[size_t(k)], int64_t(origin[k]) + dim - lo[size_t(k)]);
      if (a[size_t(k)] >= b[size_t(k)]) return;
    }
    f(a, b, value);
  };
  for (uint32_t i = 0; i < root.data()->mTableSize; ++i) {
    const auto* t = root.data()->tile(i);
    if (!t->isChild()) box(t->origin(), NanoUpper::DIM, t->value);
  }
  const NanoUpper* up = tree.nodeCount(2) ? tree.template getFirstNode<2>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(2); ++c)
    for (uint32_t i = 0; i < NanoUpper::SIZE; ++i)
      if (!up[c].data()->mChildMask.isOn(i)) box(up[c].offsetToGlobalCoord(i), NanoLower::DIM, up[c].data()->mTable[i].value);
  const NanoLower* low = tree.nodeCount(1) ? tree.template getFirstNode<1>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(1); ++c)
    for (uint32_t i = 0; i < NanoLower::SIZE; ++i)
      if (!low[c].data()->mChildMask.isOn(i)) box(low[c].offsetToGlobalCoord(i), NanoLeaf::DIM, low[c].data()->mTable[i].value);
  const NanoLeaf* leaf = tree.nodeCount(0) ? tree.template getFirstNode<0>() : nullptr;
  for (uint32_t c = 0; c < tree.nodeCount(0); ++c)
    for (uint32_t i = 0; i < NanoLeaf::SIZE; ++i) {
      const nanovdb::Coord q = leaf[c].offsetToGlobalCoord(i);
      box(q, 1, leaf[c].data()->mValues[i]);
    }
}

}  // namespace

Volume dense_from_nano(const NanoVolume& n, uint64_t max_bytes, const std::string& name) {
  Volume v;
  v.dims = n.dims;
  uint64_t count = 0;
  if (!detail::checked_volume(n.dims[0], n.dims[1], n.dims[2], detail::kMaxVoxels, &count))
    throw InputError(printable(name) + ": the active bounding box is too large to load densely");
  check_read_budget(count, 1 + int(n.has_detail()) * 3, 0, max_bytes, name);
  v.voxel_size = n.voxel_size;
  v.origin = n.origin;
  v.tiles_xz = n.tiles_xz;
  v.metadata = n.metadata;
  auto fill = [&](size_t g, std::vector<float>& out) {
    out.assign(size_t(count), 0.0f);
    visit_values(n, g, [&](const std::array<int64_t, 3>& a, const std::array<int64_t, 3>& b, float value) {
      for (int64_t z = a[2]; z < b[2]; ++z)
        for (int64_t y = a[1]; y < b[1]; ++y)
          for (int64_t x = a[0]; x < b[0]; ++x) out[v.index(uint32_t(x), uint32_t(y), uint32_t(z))] = value;
    });
  };
  fill(0, v.density);
  if (n.has_detail())
    for (int c = 0; c < 3; ++c) fill(size_t(n.detail[size_t(c)]), v.detail[size_t(c)]);
  check_finite_channels(v, name);
  build_occupancy(v);
  return v;
}

float nano_value(const NanoVolume& n, size_t g, const std::array<int32_t, 3>& ijk) {
  auto acc = grid_at(n, g)->getAccessor();
  return acc.getValue(nanovdb::Coord(ijk[0], ijk[1], ijk[2]));
}

NanoPages nano_pages(const NanoVolume& n, size_t g) {
  const NanoGrid& grid = *grid_at(n, g);
  const auto* root = grid.tree().root().data();
  const uint8_t* base = n.data();
  auto word = [base](const void* p) { return uint32_t((reinterpret_cast<const uint8_t*>(p) - base) / 4); };
  NanoPages t;
  for (int a = 0; a < 3; ++a) {
    const int32_t lo = n.index_min[size_t(a)] & ~7, hi = n.index_min[size_t(a)] + int32_t(n.dims[size_t(a)]) - 1;
    t.origin[size_t(a)] = lo;
    t.dims[size_t(a)] = uint32_t((hi - lo) / 8 + 1);
  }
  if (n.bytes() / 4 >= NanoPages::kNanoConstant) throw InputError("NanoVDB grids beyond 8 GiB: no page table");
  t.entries.resize(size_t(t.dims[0]) * t.dims[1] * t.dims[2]);
  for (uint32_t z = 0; z < t.dims[2]; ++z)
    for (uint32_t y = 0; y < t.dims[1]; ++y)
      for (uint32_t x = 0; x < t.dims[0]; ++x) {
        const nanovdb::Coord c(t.origin[0] + int32_t(8 * x), t.origin[1] + int32_t(8 * y), t.origin[2] + int32_t(8 * z));
        uint32_t e = NanoPages::kNanoConstant | word(&root->mBackground);
        const auto key = nanovdb::RootData<NanoUpper>::CoordToKey(c);
        for (uint32_t i = 0; i < root->mTableSize; ++i) {
          const auto* tile = root->tile(i);
          if (!(tile->key == key)) continue;
          if (!tile->isChild()) {
            e = NanoPages::kNanoConstant | word(&tile->value);
            break;
          }
          const auto* up = root->getChild(tile);
          const uint32_t nu = NanoUpper::CoordToOffset(c);
          if (!up->data()->mChildMask.isOn(nu)) {
            e = NanoPages::kNanoConstant | word(&up->data()->mTable[nu].value);
            break;
          }
          const NanoLower* low = up->data()->getChild(nu);
          const uint32_t nl = NanoLower::CoordToOffset(c);
          if (!low->data()->mChildMask.isOn(nl)) {
            e = NanoPages::kNanoConstant | word(&low->data()->mTable[nl].value);
            break;
          }
          e = word(low->data()->getChild(nl)->data()->mValues);
          break;
        }
        t.entries[(size_t(z) * t.dims[1] + y) * t.dims[0] + x] = e;
      }
  return t;
}

std::vector<uint8_t> nano_occupancy(const NanoVolume& n, uint32_t cell, uint32_t padding,
                                    std::array<uint32_t, 3>& od) {
  cell = std::max<uint32_t>(1, cell);
  for (int a = 0; a < 3; ++a) od[size_t(a)] = (n.dims[size_t(a)] + cell - 1) / cell;
  std::vector<uint8_t> raw(size_t{od[0]} * od[1] * od[2], 0);
  size_t bad = 0;
  visit_values(n, 0, [&](const std::array<int64_t, 3>& a, const std::array<int64_t, 3>& b, float value) {
    if (!std::isfinite(value)) ++bad;
    if (!(value > 0)) return;
    for (int64_t z = a[2] / cell; z <= (b[2] - 1) / cell; ++z)
      for (int64_t y = a[1] / cell; y <= (b[1] - 1) / cell; ++y)
        for (int64_t x = a[0] / cell; x <= (b[0] - 1) / cell; ++x) raw[(size_t(z) * od[1] + size_t(y)) * od[0] + size_t(x)] = 1;
  });
  if (bad)
    throw InputError("grid \"density\" holds " + std::to_string(bad) +
                     " NaN or infinite values; a cloud volume needs finite densities");
  dilate_occupancy(raw, od, padding, n.tiles_xz);
  return raw;
}

}  // namespace cloudgen
