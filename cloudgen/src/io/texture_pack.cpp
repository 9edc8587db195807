// Game-engine texture pack (texture_pack.h, docs/textures.md "Texture pack").
#include "cloudgen/texture_pack.h"

#include "cloudgen/detail_noise.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/view.h"
#include "cloudgen/weather_map.h"
#include "io/format_internal.h"
#include "noise3d/noise3d.h"

namespace cloudgen {

using detail::json;

namespace {

constexpr const char* kPackFormat = "cloudgen-texture-pack";
constexpr uint32_t kPackVersion = 1;
constexpr uint32_t kBaseEdge = 128;   // the base texture's longest axis (Nubis: 128^3)
constexpr uint32_t kDetailEdge = 32;  // Nubis: 32^3
constexpr uint32_t kCurlEdge = 128;   // Nubis: 128^2
// The detail texture's R channel is the viewer's render.detail texture (cloudgen/detail_noise.h, one
// definition for both; test_texture_pack checks the bytes agree), laid at the viewer's default
// render.detail_period.
constexpr double kDetailPeriodM = 200;
constexpr uint32_t kCurlCells = 4;  // Perlin cells of the curl potential per tile
constexpr uint64_t kCurlSeed = 0xc011c011ull;
constexpr const char* kRoles[4] = {"base", "detail", "curl", "weather"};

uint8_t unorm8(double f) { return uint8_t(std::lround(std::clamp(f, 0.0, 1.0) * 255.0)); }

std::string join(const std::string& dir, const std::string& name) {
  return dir.empty() || dir.back() == '/' ? dir + name : dir + "/" + name;
}


json texture_json(const MipTexture& t, const std::string& role, const std::array<double, 3>& period,
                  const json& channels) {
  static const char* formats[5] = {"", "r8_unorm", "rg8_unorm", "rgb8_unorm", "rgba8_unorm"};
  static const uint32_t vk[5] = {0, 9, 16, 23, 37};
  json j;
  j["role"] = role;
  j["ktx2"] = role + ".ktx2";
  j["raw"] = role + ".raw";
  j["dimension"] = t.is_3d ? 3 : 2;
  j["size"] = t.is_3d ? json{t.dims[0], t.dims[1], t.dims[2]} : json{t.dims[0], t.dims[1]};
  j["format"] = formats[t.channels];
  j["vk_format"] = vk[t.channels];
  j["channels"] = channels;
  j["mips"] = t.levels.size();
  j["mip_filter"] = "2x box, rounded to nearest";
  json wrap = json::array();
  for (int a = 0; a < (t.is_3d ? 3 : 2); ++a) wrap.push_back(t.wrap[a] ? "repeat" : "clamp");
  j["wrap"] = wrap;
  j["period_m"] = t.is_3d ? json{period[0], period[1], period[2]} : json{period[0], period[1]};
  json lv = json::array();
  uint64_t off = 0;
  for (size_t l = 0; l < t.levels.size(); ++l) {
    const auto d = mip_dims(t.dims, uint32_t(l));
    lv.push_back({{"offset", off}, {"bytes", t.levels[l].size()}, {"size", {d[0], d[1], d[2]}}});
    off += t.levels[l].size();
  }
  j["raw_levels"] = lv;
  return j;
}

// What the base texture's channels hold: R the shaped density, G/B/A the preset's detail channels
// (0 where the preset leaves one out).
json base_channels(const Preset& p) {
  json j;
  j["r"] = "shaped density: the " + std::string(noise3d::kind_name(p.channels[0].kind)) +
           " channel after height profile, towers, coverage and threshold";
  const char* keys[3] = {"g", "b", "a"};
  for (int c = 1; c < 4; ++c)
    j[keys[c - 1]] = p.channels[size_t(c)].enabled
                         ? "detail " + std::string(noise3d::kind_name(p.channels[size_t(c)].kind)) + " fBm (preset channel " +
                               keys[c - 1] + ", period " + std::to_string(p.channels[size_t(c)].period[0]) + " cells)"
                         : std::string("0 (the preset has no channel ") + keys[c - 1] + ")";
  return j;
}

}  // namespace

uint32_t full_mip_count(const std::array<uint32_t, 3>& dims) {
  uint32_t m = std::max({dims[0], dims[1], dims[2]}), n = 1;
  while (m > 1) m >>= 1, ++n;
  return n;
}

std::array<uint32_t, 3> mip_dims(const std::array<uint32_t, 3>& dims, uint32_t level) {
  std::array<uint32_t, 3> d;
  for (int a = 0; a < 3; ++a) d[a] = level >= 32 ? 1 : std::max<uint32_t>(1, dims[a] >> level);
  return d;
}

std::vector<uint8_t> box_downsample(const std::vector<uint8_t>& src, const std::array<uint32_t, 3>& dims, int channels) {
  const std::array<uint32_t, 3> o = mip_dims(dims, 1);
  std::array<uint32_t, 3> step;
  uint32_t count = 1;
  for (int a = 0; a < 3; ++a) {
    step[a] = dims[a] > 1 ? 2 : 1;
    count *= step[a];
  }
  std::vector<uint8_t> out = std::vector<uint8_t>(size_t(o[0]) * o[1] * o[2] * size_t(channels), uint8_t(0));
  for (uint32_t z = 0; z < o[2]; ++z)
    for (uint32_t y = 0; y < o[1]; ++y)
      for (uint32_t x = 0; x < o[0]; ++x)
        for (int c = 0; c < channels; ++c) {
          uint32_t sum = 0;
          for (uint32_t dz = 0; dz < step[2]; ++dz)
            for (uint32_t dy = 0; dy < step[1]; ++dy)
              for (uint32_t dx = 0; dx < step[0]; ++dx) {
                const size_t i = ((size_t(z) * step[2] + dz) * dims[1] + (size_t(y) * step[1] + dy)) * dims[0] +
                                 (size_t(x) * step[0] + dx);
                sum += src[i * size_t(channels) + size_t(c)];
              }
          out[((size_t(z) * o[1] + y) * o[0] + x) * size_t(channels) + size_t(c)] = uint8_t((sum + count / 2) / count);
        }
  return out;
}

void build_mips(MipTexture& t) {
  t.levels.resize(1);
  const uint32_t n = full_mip_count(t.dims);
  for (uint32_t l = 1; l < n; ++l) t.levels.push_back(box_downsample(t.levels[l - 1], mip_dims(t.dims, l - 1), t.channels));
}

TexturePack make_texture_pack(const Preset& p, int threads) {
  TexturePack pk;
  pk.preset = p;
  rescale(pk.preset, kBaseEdge);
  const Preset& q = pk.preset;
  GenerateOptions go;
  go.threads = threads;
  go.detail = true;
  go.skip_empty = false;  // detail everywhere: the texture is sampled anywhere, not only near cloud
  pk.base_volume = generate(q, go);
  const Volume& v = pk.base_volume;

  MipTexture& b = pk.base;
  b.dims = v.dims;
  b.channels = 4;
  b.wrap = {v.tiles_xz, false, v.tiles_xz};
  b.levels = {pack_texels(v, Texel::Rgba8)};
  build_mips(b);

  MipTexture& d = pk.detail;
  d.dims = {kDetailEdge, kDetailEdge, kDetailEdge};
  d.channels = 3;
  d.wrap = {true, true, true};
  const std::vector<float> oct[3] = {stretched_worley_fbm(kDetailEdge, kDetailBaseCells, kDetailOctaves, kDetailSeed),
                                     stretched_worley_fbm(kDetailEdge, 2 * kDetailBaseCells, 1, kDetailSeed + 1),
                                     stretched_worley_fbm(kDetailEdge, 4 * kDetailBaseCells, 1, kDetailSeed + 2)};
  d.levels = {std::vector<uint8_t>(oct[0].size() * 3)};
  for (size_t i = 0; i < oct[0].size(); ++i)
    for (int c = 0; c < 3; ++c) d.levels[0][i * 3 + size_t(c)] = unorm8(oct[c][i]);
  build_mips(d);

  MipTexture& c = pk.curl;
  c.dims = {kCurlEdge, kCurlEdge, 1};
  c.is_3d = false;
  c.channels = 3;
  c.wrap = {true, true, false};
  std::vector<std::array<double, 3>> cv(size_t(kCurlEdge) * kCurlEdge);
  double m = 0;
  const noise3d::Period cp{kCurlCells, 1, kCurlCells};
  for (uint32_t j = 0; j < kCurlEdge; ++j)
    for (uint32_t i = 0; i < kCurlEdge; ++i) {
      auto& e = cv[size_t(j) * kCurlEdge + i];
      e = noise3d::curl(double(i) * kCurlCells / kCurlEdge, 0.5, double(j) * kCurlCells / kCurlEdge, cp, kCurlSeed);
      for (double x : e) m = std::max(m, std::abs(x));
    }
  c.levels = {std::vector<uint8_t>(cv.size() * 3)};
  for (size_t i = 0; i < cv.size(); ++i)
    for (int k = 0; k < 3; ++k) c.levels[0][i * 3 + size_t(k)] = unorm8(0.5 + 0.5 * cv[i][size_t(k)] / (m > 0 ? m : 1.0));
  build_mips(c);

  MipTexture& w = pk.weather;
  w.dims = {v.dims[0], v.dims[2], 1};
  w.is_3d = false;
  w.channels = 3;
  w.wrap = {v.tiles_xz, v.tiles_xz, false};
  const WeatherColumns col = weather_columns(q, v.dims[0], v.dims[2], threads);
  w.levels = {std::vector<uint8_t>(size_t(col.w) * col.h * 3)};
  for (size_t i = 0; i < size_t(col.w) * col.h; ++i) {
    w.levels[0][i * 3 + 0] = unorm8(col.coverage[i]);
    w.levels[0][i * 3 + 1] = unorm8(col.type[i]);
    w.levels[0][i * 3 + 2] = unorm8(col.top[i]);
  }
  build_mips(w);
  return pk;
}

std::vector<std::string> texture_pack_files(const std::string& dir) {
  std::vector<std::string> f;
  for (const char* r : kRoles) {
    f.push_back(join(dir, std::string(r) + ".ktx2"));
    f.push_back(join(dir, std::string(r) + ".raw"));
  }
  f.push_back(join(dir, "pack.json"));
  return f;
}

bool prepare_texture_pack_dir(const std::string& dir, OutputBatch& batch) {
  const std::string where = "--texture-pack " + printable(dir);
  if (dir.empty()) throw InputError("--texture-pack: give a folder");
  struct stat st;
  if (::stat(dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw InputError(where + ": exists and is not a folder (a pack is a folder of textures)");
    return false;
  }
  if (errno != ENOENT) throw InputError(where + ": " + system_error_text(errno));
  try {
    batch.new_folder(dir, "the texture pack");
  } catch (const InputError& e) {
    throw InputError("--texture-pack " + std::string(e.what()));
  }
  return true;
}

void stage_texture_pack(const TexturePack& pk, const std::string& dir, const std::string& preset_path, OutputBatch& batch) {
  const Volume& v = pk.base_volume;
  const Look look = look_of_view(pk.preset.view, preset_path);
  json vol = detail::describe_json(v, Texel::Rgba8);
  vol.erase("size");
  vol.erase("format");
  const std::string vol_text = vol.dump(-1, ' ', false, json::error_handler_t::replace);
  const std::array<double, 3> extent{v.dims[0] * v.voxel_size, v.dims[1] * v.voxel_size, v.dims[2] * v.voxel_size};
  const MipTexture* tex[4] = {&pk.base, &pk.detail, &pk.curl, &pk.weather};
  const std::array<double, 3> period[4] = {extent,
                                           {kDetailPeriodM, kDetailPeriodM, kDetailPeriodM},
                                           {extent[0], extent[0], 0},
                                           {extent[0], extent[2], 0}};
  const json channels[4] = {
      base_channels(pk.preset),
      {{"r", "Worley fBm, 3 octaves at 4, 8, 16 cells a tile: the viewer's render.detail texture"},
       {"g", "Worley, 8 cells a tile"},
       {"b", "Worley, 16 cells a tile"}},
      {{"r", "curl x"}, {"g", "curl y"}, {"b", "curl z"}},
      {{"r", "coverage"}, {"g", "cloud type (0 stratus, 0.5 cumulus, 1 cumulonimbus)"}, {"b", "cloud top, fraction of the height"}}};
  json doc;
  doc["format"] = kPackFormat;
  doc["version"] = kPackVersion;
  doc["generator"] = std::string("cloudgen ") + CLOUDGEN_VERSION;
  doc["preset"] = pk.preset.name;
  doc["preset_hash"] = preset_hash(pk.preset);
  doc["extent_m"] = extent;
  doc["origin_m"] = {v.origin[0], v.origin[1], v.origin[2]};
  doc["tiles_xz"] = v.tiles_xz;
  doc["textures"] = json::array();
  for (int i = 0; i < 4; ++i) doc["textures"].push_back(texture_json(*tex[i], kRoles[i], period[i], channels[i]));
  doc["textures"][2]["encoding"] = "value = (byte / 255 * 2 - 1), a unit-free direction field; scale as you like";
  doc["combine"] = {
      {"erosion", look.erosion},
      {"density_scale", look.density},
      {"detail_strength", 0.0},
      {"formula",
       "h = height fraction in the box (0 bottom, 1 top); base = R (trilinear); when G, B and A are all present: "
       "d = 0.625 G + 0.25 B + 0.125 A; "
       "e = erosion * mix(1 - d, d, clamp(5 h, 0, 1)); density = clamp((base - e) / max(1 - e, 1e-4), 0, 1); "
       "then, with render-time detail of strength s > 0: f = detail.R at world position / detail period_m, "
       "e2 = s * mix(1 - f, f, clamp(5 h, 0, 1)), density = clamp((density - e2) / max(1 - e2, 1e-4), 0, 1); "
       "finally density *= density_scale, extinction = density * sigma_t (1/m; the viewer's default 0.5 / voxel size). "
       "R already holds coverage, height profile and towers (box presets); "
       "the weather and curl textures are for engines that shape or distort at render time"},
      {"glsl",
       {"viewer/shaders/medium.glsl cloud_density_seen", "cloudgen/include/cloudgen/erosion.glsl erosion_detail",
        "erosion_threshold", "eroded_base"}}};
  for (int i = 0; i < 4; ++i) {
    const MipTexture& t = *tex[i];
    const std::vector<uint8_t> k = ktx2_bytes(t, i == 0 ? vol_text : "");
    batch.stage(join(dir, std::string(kRoles[i]) + ".ktx2"), [&](const std::string& tmp) { write_file_bytes(tmp, k.data(), k.size()); });
    std::vector<uint8_t> raw;
    for (const auto& l : t.levels) raw.insert(raw.end(), l.begin(), l.end());
    batch.stage(join(dir, std::string(kRoles[i]) + ".raw"), [&](const std::string& tmp) { write_file_bytes(tmp, raw.data(), raw.size()); });
  }
  detail::stage_json(batch, join(dir, "pack.json"), doc);
}

bool is_pack_json(const std::string& text) {
  if (text.find(kPackFormat) == std::string::npos) return false;
  try {
    const json j = parse_json_checked(text, "pack.json");
    return j.is_object() && j.contains("format") && j["format"].is_string() && j["format"].get<std::string>() == kPackFormat;
  } catch (...) {
    return false;
  }
}

PackDescription parse_pack_json(const std::string& text, const std::string& where_in) {
  const std::string where = printable(where_in);
  const json j = parse_json_checked(text, where);
  if (!j.is_object()) throw InputError(where + ": a texture pack's pack.json is a JSON object");
  const detail::FieldReader f(j, where);
  if (f.string("format") != kPackFormat)
    throw InputError(where + ": \"format\" is " + json_excerpt(j["format"]) + ", expected \"" + kPackFormat + "\"");
  f.integer("version", 0, kPackVersion, kPackVersion);
  PackDescription d;
  d.preset = f.string("preset");
  d.preset_hash = f.has("preset_hash") ? f.string("preset_hash") : "";
  d.extent_m = f.vec3("extent_m", 1e-6, 1e9);
  if (!f.has("textures") || !f.at("textures").is_array() || f.at("textures").size() != 4)
    throw InputError(where + ": \"textures\" must be an array of the 4 textures base, detail, curl, weather");
  const json& ts = f.at("textures");
  for (size_t i = 0; i < 4; ++i) {
    const std::string tw = where + ": textures[" + std::to_string(i) + "]";
    if (!ts[i].is_object()) throw InputError(tw + ": is not an object");
    const detail::FieldReader t(ts[i], tw);
    PackTexture pt;
    pt.role = t.string("role");
    if (pt.role != kRoles[i])
      throw InputError(tw + ": \"role\" is \"" + printable(pt.role) + "\", expected \"" + kRoles[i] +
                       "\" (the textures are base, detail, curl, weather in that order)");
    for (const char* key : {"ktx2", "raw"}) {
      const std::string name = t.string(key);
      if (name.empty() || name.size() > 255 || name.find('/') != std::string::npos || name.find('\\') != std::string::npos ||
          name == "." || name == ".." || name.find('\0') != std::string::npos)
        throw InputError(tw + ": \"" + key + "\" is \"" + printable(name) +
                         "\": a file name inside the pack's folder is expected (no folders, 1 to 255 characters)");
      (std::string(key) == "ktx2" ? pt.ktx2 : pt.raw) = name;
    }
    const uint32_t dim = t.integer("dimension", 0, 2, 3);
    pt.is_3d = dim == 3;
    if (i < 2 && !pt.is_3d) throw InputError(tw + ": \"dimension\" is 2, the " + pt.role + " texture is 3D");
    if (i >= 2 && pt.is_3d) throw InputError(tw + ": \"dimension\" is 3, the " + pt.role + " texture is 2D");
    if (!t.has("size") || !t.at("size").is_array() || t.at("size").size() != dim)
      throw InputError(tw + ": \"size\" must be an array of " + std::to_string(dim) + " integers");
    const json& sz = t.at("size");
    for (uint32_t a = 0; a < dim; ++a) {
      if (!sz[a].is_number_unsigned() || sz[a].get<uint64_t>() < 1 || sz[a].get<uint64_t>() > 4096)
        throw InputError(tw + ": \"size\"[" + std::to_string(a) + "] is " + json_excerpt(sz[a]) +
                         ", expected an integer in [1, 4096]");
      pt.dims[a] = sz[a].get<uint32_t>();
    }
    const std::string fmt = t.string("format");
    static const char* formats[5] = {"", "r8_unorm", "rg8_unorm", "rgb8_unorm", "rgba8_unorm"};
    const int want = i == 0 ? 4 : 3;
    if (fmt != formats[want])
      throw InputError(tw + ": \"format\" is \"" + printable(fmt) + "\", the " + pt.role + " texture is " + formats[want]);
    pt.channels = want;
    pt.mips = t.integer("mips", 0, 1, full_mip_count(pt.dims));
    if (!t.has("period_m") || !t.at("period_m").is_array() || t.at("period_m").size() != dim)
      throw InputError(tw + ": \"period_m\" must be an array of " + std::to_string(dim) + " numbers");
    for (uint32_t a = 0; a < dim; ++a) {
      const json& pv = t.at("period_m")[a];
      if (!pv.is_number() || !(pv.get<double>() > 0) || pv.get<double>() > 1e9)
        throw InputError(tw + ": \"period_m\"[" + std::to_string(a) + "] is " + json_excerpt(pv) +
                         ", expected metres in (0, 1e9]");
      pt.period_m[a] = pv.get<double>();
    }
    d.textures.push_back(pt);
  }
  return d;
}

std::string texture_pack_base(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (1 << 20)) return "";
  const std::vector<uint8_t> bytes = read_file_bytes(path, size_t(1) << 20);
  const std::string text(bytes.begin(), bytes.end());
  if (!is_pack_json(text)) return "";
  const PackDescription d = parse_pack_json(text, path);
  const size_t slash = path.find_last_of('/');
  return (slash == std::string::npos ? "" : path.substr(0, slash + 1)) + d.textures[0].ktx2;
}

Volume read_texture_pack(const std::string& path, uint64_t max_bytes) {
  const std::vector<uint8_t> text = read_file_bytes(path, size_t(1) << 20);
  const PackDescription d = parse_pack_json(std::string(text.begin(), text.end()), path);
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  Volume base;
  for (size_t i = 0; i < d.textures.size(); ++i) {
    const PackTexture& pt = d.textures[i];
    const std::string file = dir + pt.ktx2;
    const std::vector<uint8_t> bytes = read_file_bytes(file, size_t(std::min<uint64_t>(max_bytes * 2, uint64_t(1) << 36)));
    const MipTexture t = parse_ktx2_mips(bytes, file, max_bytes);
    const std::string at = printable(file) + " (" + pt.role + " in " + printable(path) + ")";
    if (t.dims != pt.dims || t.is_3d != pt.is_3d || t.channels != pt.channels || t.levels.size() != pt.mips)
      throw InputError(at + ": the KTX2 holds " + std::to_string(t.dims[0]) + "x" + std::to_string(t.dims[1]) + "x" +
                       std::to_string(t.dims[2]) + ", " + std::to_string(t.channels) + " channels, " +
                       std::to_string(t.levels.size()) + " mips; pack.json declares " + std::to_string(pt.dims[0]) + "x" +
                       std::to_string(pt.dims[1]) + "x" + std::to_string(pt.dims[2]) + ", " +
                       std::to_string(pt.channels) + " channels, " + std::to_string(pt.mips) + " mips");
    for (size_t l = 1; l < t.levels.size(); ++l)
      if (box_downsample(t.levels[l - 1], mip_dims(t.dims, uint32_t(l - 1)), t.channels) != t.levels[l])
        throw InputError(at + ": mip " + std::to_string(l) + " is not the 2x box filter of mip " + std::to_string(l - 1));
    uint64_t raw_bytes = 0;
    for (const auto& lv : t.levels) raw_bytes += lv.size();
    struct stat st;
    const std::string raw = dir + pt.raw;
    if (::stat(raw.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || uint64_t(st.st_size) != raw_bytes)
      throw InputError(printable(raw) + " (" + pt.role + " raw in " + printable(path) + "): missing, or not the " +
                       std::to_string(raw_bytes) + " bytes of its " + std::to_string(t.levels.size()) + " mips");
    if (i == 0) {
      base = parse_ktx2(bytes, file, max_bytes);
      const double vs = d.extent_m[0] / pt.dims[0];
      if (std::abs(base.voxel_size - vs) > 1e-6 * vs)
        throw InputError(at + ": voxel size " + std::to_string(base.voxel_size) + " m disagrees with extent_m / size (" +
                         std::to_string(vs) + " m)");
    }
  }
  base.metadata.push_back({"texture_pack", printable(path)});
  return base;
}

}  // namespace cloudgen
