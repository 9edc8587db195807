// Raw RGBA 3D textures: NAME.raw (texels, x fastest), NAME.json (sidecar: size, format, voxel
// size, origin, tiling, channels, metadata) and NAME.occupancy.raw (the coarse occupancy grid).
#include <algorithm>
#include <filesystem>

#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "io/format_internal.h"

namespace cloudgen {

namespace fs = std::filesystem;
using detail::json;

namespace {

std::string sidecar_of(const std::string& raw) { return (fs::path(raw).replace_extension(".json")).string(); }
std::string occupancy_of(const std::string& raw) {
  return (fs::path(raw).replace_extension("").string() + ".occupancy.raw");
}

}  // namespace

void write_raw(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
  const std::vector<uint8_t> texels = pack_texels(v, o.texel);
  json j = detail::describe_json(v, o.texel);
  j["file"] = fs::path(path).filename().string();
  batch.stage(path, [&](const std::string& tmp) { write_file_bytes(tmp, texels.data(), texels.size()); });
  if (!v.occupancy.empty()) {
    const std::string occ = occupancy_of(path);
    j["occupancy"] = {{"file", fs::path(occ).filename().string()},
                      {"size", {v.occupancy_dims[0], v.occupancy_dims[1], v.occupancy_dims[2]}},
                      {"format", "r8 (0 empty, 1 occupied)"},
                      {"cell", v.occupancy_cell},
                      {"padding", v.occupancy_padding}};
    batch.stage(occ, [&](const std::string& tmp) { write_file_bytes(tmp, v.occupancy.data(), v.occupancy.size()); });
  }
  detail::stage_json(batch, sidecar_of(path), j);
}

Volume parse_raw(const std::string& sidecar_text, const std::vector<uint8_t>& bytes, const std::string& name,
                 const std::vector<uint8_t>* occupancy_bytes, uint64_t max_bytes) {
  const std::string side = printable(sidecar_of(name)), raw = printable(name);
  const json j = parse_json_checked(sidecar_text, side);
  if (!j.is_object() || !j.contains("format") || !j.contains("size"))
    throw InputError(side + ": not a cloudgen texture sidecar (no \"format\"/\"size\"; a `cloudgen noise` cube is a "
                            "single float channel, not a cloud texture)");
  const detail::FieldReader f(j, side);
  Volume v;
  const Texel texel = parse_texel(f.string("format"), side + ": field \"format\"");
  v.dims = f.ivec3("size", 1, detail::kMaxEdge);
  uint64_t voxels = 0;
  if (!detail::checked_volume(v.dims[0], v.dims[1], v.dims[2], detail::kMaxVoxels, &voxels))
    f.fail("size", "holds more than 2^34 voxels");
  v.voxel_size = f.number("voxel_size", 1.0, 1e-9, 1e9);
  if (f.has("origin")) v.origin = f.vec3("origin", -1e12, 1e12);
  v.tiles_xz = f.boolean("tiles_xz", false);
  const uint64_t want = voxels * texel_bytes(texel);
  if (bytes.size() != want)
    throw InputError(raw + ": the texture holds " + std::to_string(bytes.size()) + " bytes but the sidecar's size " +
                     std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) + " " +
                     texel_name(texel) + " needs " + std::to_string(want));
  int channels = 1;
  if (f.has("channels")) {
    const json& ch = f.at("channels");
    if (!ch.is_object()) f.fail("channels", "should be an object like {\"r\": \"density\", \"g\": \"detail_g\"}");
    const detail::FieldReader cf(ch, side + ": field \"channels\"");
    const char* keys[] = {"g", "b", "a"};
    for (int c = 0; c < 3; ++c)
      if (cf.has(keys[c]) && !cf.string(keys[c]).empty()) {
        channels = c + 2;
        v.detail_names[c] = cf.string(keys[c]);
      }
  }
  check_read_budget(voxels, channels, 0, max_bytes, name);
  detail::unpack_texels(v, bytes.data(), texel, channels);
  check_finite_channels(v, name);
  if (f.has("metadata")) {
    const json& m = f.at("metadata");
    if (!m.is_object()) f.fail("metadata", "should be an object of strings");
    for (auto& [k, val] : m.items()) v.metadata.push_back({k, val.is_string() ? val.get<std::string>() : val.dump()});
  }
  if (f.has("occupancy")) {
    const json& oj = f.at("occupancy");
    if (!oj.is_object()) f.fail("occupancy", "should be an object");
    const detail::FieldReader of(oj, side + ": field \"occupancy\"");
    v.occupancy_cell = of.integer("cell", 8, 1, 256);
    v.occupancy_padding = of.integer("padding", 2, 0, 16);
    if (occupancy_bytes && !occupancy_bytes->empty()) {
      // The file that write_raw wrote is used as it is, after checking that it is the grid of this
      // density: the right size, 0/1 values, and every cell holding density marked occupied (a
      // stale or damaged file could otherwise hide cloud from the marcher).
      std::array<uint32_t, 3> od = of.ivec3("size", 1, detail::kMaxEdge);
      for (int a = 0; a < 3; ++a)
        if (od[a] != (v.dims[a] + v.occupancy_cell - 1) / v.occupancy_cell)
          of.fail("size", "does not match the texture size " + std::to_string(v.dims[a]) + " / cell " +
                              std::to_string(v.occupancy_cell) + " on axis " + "xyz"[a]);
      const size_t cells = size_t(od[0]) * od[1] * od[2];
      if (occupancy_bytes->size() != cells)
        throw InputError(side + ": the occupancy file holds " + std::to_string(occupancy_bytes->size()) +
                         " bytes but its size needs " + std::to_string(cells));
      if (std::any_of(occupancy_bytes->begin(), occupancy_bytes->end(), [](uint8_t b) { return b > 1; }))
        throw InputError(side + ": the occupancy file holds values other than 0 and 1");
      const uint32_t c = v.occupancy_cell;
      for (uint32_t z = 0; z < v.dims[2]; ++z)
        for (uint32_t y = 0; y < v.dims[1]; ++y)
          for (uint32_t x = 0; x < v.dims[0]; ++x)
            if (v.density[v.index(x, y, z)] > 0 &&
                !(*occupancy_bytes)[(size_t(z / c) * od[1] + y / c) * od[0] + x / c])
              throw InputError(side + ": the occupancy file marks cell (" + std::to_string(x / c) + ", " +
                               std::to_string(y / c) + ", " + std::to_string(z / c) +
                               ") empty but it holds density; the file is stale or damaged (delete it to rebuild)");
      v.occupancy_dims = od;
      v.occupancy = *occupancy_bytes;
      return v;
    }
  }
  build_occupancy(v);
  return v;
}

Volume read_raw(const std::string& path_in, uint64_t max_bytes) {
  std::string raw = path_in, side = path_in;
  if (fs::path(path_in).extension() == ".json") raw = (fs::path(path_in).replace_extension(".raw")).string();
  else side = sidecar_of(path_in);
  if (!fs::exists(side))
    throw InputError(printable(raw) + ": missing sidecar " + printable(side) + " (size and format live there)");
  const std::vector<uint8_t> side_bytes = read_file_bytes(side, size_t(1) << 24);
  const std::string text(side_bytes.begin(), side_bytes.end());
  std::vector<uint8_t> occ;
  const std::string occ_path = occupancy_of(raw);
  if (fs::exists(occ_path)) occ = read_file_bytes(occ_path, size_t(1) << 32);
  return parse_raw(text, read_file_bytes(raw, size_t(std::min<uint64_t>(max_bytes, uint64_t(1) << 40))), raw, &occ,
                   max_bytes);
}

}  // namespace cloudgen
