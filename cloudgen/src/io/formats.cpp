// The format registry: names, extensions, which files each format writes, dispatch, texel
// packing, `cloudgen info`, and the typed sidecar field reader.
#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "io/format_internal.h"

namespace cloudgen {

namespace fs = std::filesystem;
using detail::json;

// ---------------------------------------------------------------------------------------------
// Name tables: one per enum; parse and print both read them.
namespace {

constexpr TexelInfo kTexels[] = {
    {Texel::Rgba8, "rgba8", 4, 37, 1},      // VK_FORMAT_R8G8B8A8_UNORM
    {Texel::Rgba16f, "rgba16f", 8, 97, 2},  // VK_FORMAT_R16G16B16A16_SFLOAT
    {Texel::Rgba32f, "rgba32f", 16, 109, 4},  // VK_FORMAT_R32G32B32A32_SFLOAT
};

struct CompressionName {
  VdbCompression c;
  const char* name;
};
constexpr CompressionName kCompressions[] = {
    {VdbCompression::Blosc, "blosc"}, {VdbCompression::Zip, "zip"}, {VdbCompression::None, "none"}};

struct PrecisionName {
  NvdbPrecision p;
  const char* name;
};
constexpr PrecisionName kPrecisions[] = {{NvdbPrecision::Float, "float"},
                                         {NvdbPrecision::Fp16, "fp16"},
                                         {NvdbPrecision::Fp8, "fp8"},
                                         {NvdbPrecision::Fp4, "fp4"},
                                         {NvdbPrecision::FpN, "fpn"}};

struct FormatName {
  Format f;
  const char* name;
  const char* ext;
};
constexpr FormatName kFormats[] = {{Format::Vdb, "vdb", ".vdb"},
                                   {Format::Raw, "raw", ".raw"},
                                   {Format::Ktx2, "ktx2", ".ktx2"},
                                   {Format::AtlasPng, "atlas-png", ".png"},
                                   {Format::AtlasExr, "atlas-exr", ".exr"},
                                   {Format::Nvdb, "nvdb", ".nvdb"}};

template <class Table, class Get>
std::string choices(const Table& t, Get get) {
  std::string s;
  for (const auto& e : t) s += (s.empty() ? "" : ", ") + std::string(get(e));
  return s;
}

}  // namespace

const TexelInfo& texel_info(Texel t) {
  for (const TexelInfo& i : kTexels)
    if (i.texel == t) return i;
  throw Error("unknown texel enum value");
}
const char* texel_name(Texel t) { return texel_info(t).name; }
size_t texel_bytes(Texel t) { return texel_info(t).bytes; }
void check_lod_levels(uint32_t levels, const uint32_t dims[3]) {
  const uint32_t most = max_lod_levels(dims);
  if (levels > most)
    throw InputError("export.vdb.lod (--lod): " + std::to_string(levels) + " is more levels than a " +
                     std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                     " volume has; allowed: 0 .. " + std::to_string(most) + " (level " + std::to_string(most) +
                     " is one voxel along the longest axis)");
}

Texel parse_texel(const std::string& name, const std::string& where) {
  for (const TexelInfo& i : kTexels)
    if (name == i.name) return i.texel;
  throw InputError(where + ": \"" + printable(name) + "\" is not a texel format; expected one of " +
                   choices(kTexels, [](const TexelInfo& i) { return i.name; }));
}
bool texel_from_vk(uint32_t vk, Texel* out) {
  for (const TexelInfo& i : kTexels)
    if (i.vk_format == vk) return *out = i.texel, true;
  return false;
}

const char* vdb_compression_name(VdbCompression c) {
  for (const auto& e : kCompressions)
    if (e.c == c) return e.name;
  return "?";
}
VdbCompression parse_vdb_compression(const std::string& name, const std::string& where) {
  for (const auto& e : kCompressions)
    if (name == e.name) return e.c;
  throw InputError(where + ": \"" + printable(name) + "\" is not a compression; expected one of " +
                   choices(kCompressions, [](const CompressionName& e) { return e.name; }));
}

const char* nvdb_precision_name(NvdbPrecision p) {
  for (const auto& e : kPrecisions)
    if (e.p == p) return e.name;
  return "?";
}
NvdbPrecision parse_nvdb_precision(const std::string& name, const std::string& where) {
  for (const auto& e : kPrecisions)
    if (name == e.name) return e.p;
  throw InputError(where + ": \"" + printable(name) + "\" is not a NanoVDB precision; expected one of " +
                   choices(kPrecisions, [](const PrecisionName& e) { return e.name; }));
}

Format parse_format(const std::string& s) {
  for (const auto& e : kFormats)
    if (s == e.name) return e.f;
  throw InputError("--format: \"" + printable(s) + "\" is not a format; expected one of " +
                   choices(kFormats, [](const FormatName& e) { return e.name; }));
}

Format format_from_path(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  for (const auto& e : kFormats)
    if (ext == e.ext) return e.f;
  throw InputError(printable(path) + ": cannot tell the format from the extension \"" + printable(ext) +
                   "\"; use .vdb, .nvdb, .raw, .ktx2, .png or .exr, or pass --format");
}

const char* format_name(Format f) {
  for (const auto& e : kFormats)
    if (e.f == f) return e.name;
  return "?";
}

bool needs_detail(Format f, const ExportOptions& o) { return (f != Format::Vdb && f != Format::Nvdb) || o.vdb_detail; }

// ---------------------------------------------------------------------------------------------

std::vector<OutputFile> output_files(const std::string& path, Format f, bool with_occupancy) {
  std::vector<OutputFile> out{{path, std::string(format_name(f)) + " output " + path}};
  const std::string side = fs::path(path).replace_extension(".json").string();
  if (f == Format::Raw) {
    out.push_back({side, "the sidecar of " + path});
    if (with_occupancy)
      out.push_back({fs::path(path).replace_extension("").string() + ".occupancy.raw", "the occupancy of " + path});
  } else if (f == Format::AtlasPng || f == Format::AtlasExr) {
    out.push_back({side, "the sidecar of " + path});
  }
  return out;
}

void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o, OutputBatch& batch) {
  switch (f) {
    case Format::Vdb: return write_vdb(v, path, o, batch);
    case Format::Nvdb: return write_nvdb(v, path, o, batch);
    case Format::Raw: return write_raw(v, path, o, batch);
    case Format::Ktx2: return write_ktx2(v, path, o, batch);
    case Format::AtlasPng:
    case Format::AtlasExr: return write_atlas(v, path, f, batch);
  }
}

void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o) {
  OutputBatch batch;
  write_volume(v, path, f, o, batch);
  batch.commit();
}
void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o) {
  write_volume(v, path, Format::Vdb, o);
}
void write_raw(const Volume& v, const std::string& path, const ExportOptions& o) {
  write_volume(v, path, Format::Raw, o);
}
void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o) {
  write_volume(v, path, Format::Ktx2, o);
}
void write_atlas(const Volume& v, const std::string& path, Format f) { write_volume(v, path, f, ExportOptions{}); }

void check_finite_channels(const Volume& v, const std::string& name) {
  const std::vector<float>* ch[4] = {&v.density, &v.detail[0], &v.detail[1], &v.detail[2]};
  const char* names[4] = {"density", v.detail_names[0].c_str(), v.detail_names[1].c_str(), v.detail_names[2].c_str()};
  for (int c = 0; c < 4; ++c) {
    const size_t bad = size_t(std::count_if(ch[c]->begin(), ch[c]->end(), [](float f) { return !std::isfinite(f); }));
    if (bad)
      throw InputError(printable(name) + ": channel \"" + printable(names[c]) + "\" holds " + std::to_string(bad) +
                       " NaN or infinite values; a cloud volume needs finite densities (`cloudgen info` lists them)");
  }
}

void check_read_budget(uint64_t voxels, int channels, uint64_t extra, uint64_t max_bytes, const std::string& name) {
  const long double need = (long double)voxels * 4 * channels + extra;
  if (need <= (long double)max_bytes) return;
  char buf[160];
  std::snprintf(buf, sizeof buf, "needs about %.2f GiB of memory to load densely, more than the %.2f GiB allowed",
                double(need / (1u << 30)), double(max_bytes) / (1u << 30));
  throw InputError(printable(name) + ": " + std::to_string(voxels) + " voxels x " + std::to_string(channels) +
                   " channels " + buf + " (raise the memory limit, e.g. --max-memory, or export at a lower resolution)");
}

Volume read_volume(const std::string& path, uint64_t max_bytes) {
  if (!fs::exists(fs::symlink_status(path))) throw InputError(printable(path) + ": no such file");
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".vdb") return read_vdb(path, max_bytes);
  if (ext == ".nvdb") return read_nvdb_volume(path, max_bytes);
  if (ext == ".ktx2") return read_ktx2(path, max_bytes);
  if (ext == ".raw" || ext == ".json") return read_raw(path, max_bytes);
  throw InputError(printable(path) + ": unknown volume type \"" + printable(ext) +
                   "\"; expected .vdb, .nvdb, .raw (+ .json sidecar) or .ktx2");
}

namespace {

/// min/max over finite values, plus counts of NaN, infinite and non-zero values.
struct ChannelStats {
  size_t nan = 0, inf = 0, nonzero = 0, finite = 0;
  float lo = 0, hi = 0;
};
ChannelStats channel_stats(const std::vector<float>& c) {
  ChannelStats s;
  for (float f : c) {
    if (std::isnan(f)) {
      ++s.nan;
      continue;
    }
    if (std::isinf(f)) {
      ++s.inf;
      ++s.nonzero;
      continue;
    }
    if (s.finite++ == 0) s.lo = s.hi = f;
    s.lo = std::min(s.lo, f), s.hi = std::max(s.hi, f);
    s.nonzero += f != 0;
  }
  return s;
}

}  // namespace

std::string describe_file(const std::string& path) {
  if (!fs::exists(fs::symlink_status(path))) throw InputError(printable(path) + ": no such file");
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".vdb") return describe_vdb(path);
  Volume v = read_volume(path);
  std::ostringstream o;
  o << printable(path) << "\n  size " << v.dims[0] << " x " << v.dims[1] << " x " << v.dims[2]
    << " voxels, voxel size " << v.voxel_size << " m, origin (" << v.origin[0] << ", " << v.origin[1] << ", "
    << v.origin[2] << ")" << (v.tiles_xz ? ", tiles in x and z" : "") << "\n";
  auto range = [&](const char* name, const std::vector<float>& c) {
    if (c.empty()) return;
    const ChannelStats s = channel_stats(c);
    o << "  " << name << ": ";
    if (s.finite) o << "min " << s.lo << ", max " << s.hi << ", ";
    o << "non-zero " << s.nonzero << " (" << (100.0 * s.nonzero / c.size()) << "%)";
    if (s.nan || s.inf) o << ", NaN " << s.nan << ", infinite " << s.inf << " (not valid densities)";
    o << "\n";
  };
  range("R density", v.density);
  range("G detail", v.detail[0]);
  range("B detail", v.detail[1]);
  range("A detail", v.detail[2]);
  size_t occ = size_t(std::count(v.occupancy.begin(), v.occupancy.end(), uint8_t(1)));
  o << "  occupancy " << v.occupancy_dims[0] << " x " << v.occupancy_dims[1] << " x " << v.occupancy_dims[2]
    << " cells of " << v.occupancy_cell << "^3, padding " << v.occupancy_padding << ", " << occ << " occupied\n";
  for (auto& [k, val] : v.metadata) o << "  " << printable(k) << ": " << printable(val) << "\n";
  return o.str();
}

std::vector<uint8_t> pack_texels(const Volume& v, Texel t) {
  const size_t n = v.voxel_count(), tb = texel_bytes(t);
  std::vector<uint8_t> out(n * tb);
  const float* ch[4] = {v.density.data(), v.detail[0].empty() ? nullptr : v.detail[0].data(),
                        v.detail[1].empty() ? nullptr : v.detail[1].data(),
                        v.detail[2].empty() ? nullptr : v.detail[2].data()};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 4; ++c) {
      const float f = ch[c] ? ch[c][i] : 0.0f;
      switch (t) {
        case Texel::Rgba8: out[i * 4 + c] = uint8_t(std::lround(std::clamp(f, 0.0f, 1.0f) * 255.0f)); break;
        case Texel::Rgba16f: {
          const uint16_t h = Imath::half(f).bits();
          std::memcpy(&out[i * 8 + c * 2], &h, 2);
          break;
        }
        case Texel::Rgba32f: std::memcpy(&out[i * 16 + c * 4], &f, 4); break;
      }
    }
  return out;
}

namespace detail {

void unpack_texels(Volume& v, const uint8_t* data, Texel t, int channels) {
  const size_t n = v.voxel_count();
  v.density.resize(n);
  for (int c = 0; c < 3; ++c) v.detail[c].assign(c + 1 < channels ? n : 0, 0.0f);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c) {
      float f = 0;
      switch (t) {
        case Texel::Rgba8: f = data[i * 4 + c] / 255.0f; break;
        case Texel::Rgba16f: {
          uint16_t h;
          std::memcpy(&h, data + i * 8 + c * 2, 2);
          Imath::half hv;
          hv.setBits(h);
          f = float(hv);
          break;
        }
        case Texel::Rgba32f: std::memcpy(&f, data + i * 16 + c * 4, 4); break;
      }
      (c == 0 ? v.density : v.detail[c - 1])[i] = f;
    }
}

json describe_json(const Volume& v, Texel t) {
  json j;
  j["size"] = {v.dims[0], v.dims[1], v.dims[2]};
  j["format"] = texel_name(t);
  j["memory_order"] = "x fastest, then y (up), then z; texel = R, G, B, A";
  j["voxel_size"] = v.voxel_size;
  j["origin"] = {v.origin[0], v.origin[1], v.origin[2]};
  j["tiles_xz"] = v.tiles_xz;
  j["channels"] = {{"r", "density"},
                   {"g", v.detail[0].empty() ? "" : v.detail_names[0]},
                   {"b", v.detail[1].empty() ? "" : v.detail_names[1]},
                   {"a", v.detail[2].empty() ? "" : v.detail_names[2]}};
  json meta = json::object();
  for (auto& [k, val] : v.metadata) meta[k] = val;
  j["metadata"] = meta;
  return j;
}

void stage_json(OutputBatch& batch, const std::string& path, const json& j) {
  const std::string s = j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
  batch.stage(path, [&](const std::string& tmp) { write_file_bytes(tmp, s.data(), s.size()); });
}

bool checked_volume(uint64_t x, uint64_t y, uint64_t z, uint64_t limit, uint64_t* out) {
  uint64_t xy = 0, xyz = 0;
  if (__builtin_mul_overflow(x, y, &xy) || __builtin_mul_overflow(xy, z, &xyz) || xyz > limit) return false;
  *out = xyz;
  return true;
}

const json& FieldReader::at(const char* key) const {
  if (!has(key)) fail(key, "is missing");
  return j_.at(key);
}
void FieldReader::fail(const std::string& key, const std::string& what) const {
  throw InputError(where_ + ": field \"" + key + "\" " + what);
}
std::string FieldReader::string(const char* key) const {
  const json& v = at(key);
  if (!v.is_string()) fail(key, "should be a string, got " + json_excerpt(v));
  return v.get<std::string>();
}
bool FieldReader::boolean(const char* key, bool def) const {
  if (!has(key)) return def;
  const json& v = at(key);
  if (!v.is_boolean()) fail(key, "should be true or false, got " + json_excerpt(v));
  return v.get<bool>();
}
double FieldReader::number_value(const json& v, const std::string& key, double lo, double hi) const {
  if (!v.is_number()) fail(key, "should be a number, got " + json_excerpt(v));
  const double d = v.get<double>();
  if (!std::isfinite(d) || d < lo || d > hi) {
    std::ostringstream r;
    r << "is " << d << "; allowed: a number in [" << lo << ", " << hi << "]";
    fail(key, r.str());
  }
  return d;
}
uint32_t FieldReader::integer_value(const json& v, const std::string& key, uint32_t lo, uint32_t hi) const {
  const std::string allowed = "; allowed: an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!v.is_number_integer())
    fail(key, "should be an integer, got " + json_excerpt(v) + allowed);
  const bool ok = v.is_number_unsigned() ? v.get<uint64_t>() >= lo && v.get<uint64_t>() <= hi
                                         : v.get<int64_t>() >= int64_t(lo) && v.get<int64_t>() <= int64_t(hi);
  if (!ok) fail(key, "is " + json_excerpt(v) + allowed);
  return uint32_t(v.get<int64_t>());
}
double FieldReader::number(const char* key, double def, double lo, double hi) const {
  return has(key) ? number_value(at(key), key, lo, hi) : def;
}
uint32_t FieldReader::integer(const char* key, uint32_t def, uint32_t lo, uint32_t hi) const {
  return has(key) ? integer_value(at(key), key, lo, hi) : def;
}
std::array<uint32_t, 3> FieldReader::ivec3(const char* key, uint32_t lo, uint32_t hi) const {
  const json& v = at(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "should be an array of 3 integers, got " + json_excerpt(v));
  std::array<uint32_t, 3> out{};
  for (int a = 0; a < 3; ++a) out[a] = integer_value(v[a], std::string(key) + "[" + std::to_string(a) + "]", lo, hi);
  return out;
}
std::array<double, 3> FieldReader::vec3(const char* key, double lo, double hi) const {
  const json& v = at(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "should be an array of 3 numbers, got " + json_excerpt(v));
  std::array<double, 3> out{};
  for (int a = 0; a < 3; ++a) out[a] = number_value(v[a], std::string(key) + "[" + std::to_string(a) + "]", lo, hi);
  return out;
}

}  // namespace detail
}  // namespace cloudgen
