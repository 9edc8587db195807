// Format dispatch, atomic writes, raw textures with a JSON sidecar, KTX2 and slice atlases.
#include "cloudgen/io.h"

#include <Imath/half.h>
#include <ImfRgbaFile.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

namespace cloudgen {

namespace fs = std::filesystem;
using json = nlohmann::json;

Format parse_format(const std::string& s) {
  if (s == "vdb") return Format::Vdb;
  if (s == "raw") return Format::Raw;
  if (s == "ktx2") return Format::Ktx2;
  if (s == "atlas-png") return Format::AtlasPng;
  if (s == "atlas-exr") return Format::AtlasExr;
  throw InputError("--format: \"" + s + "\" is not a format; expected one of vdb, raw, ktx2, atlas-png, atlas-exr");
}

Format format_from_path(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".vdb") return Format::Vdb;
  if (ext == ".raw") return Format::Raw;
  if (ext == ".ktx2") return Format::Ktx2;
  if (ext == ".png") return Format::AtlasPng;
  if (ext == ".exr") return Format::AtlasExr;
  throw InputError(path + ": cannot tell the format from the extension \"" + ext +
                   "\"; use .vdb, .raw, .ktx2, .png or .exr, or pass --format");
}

const char* format_name(Format f) {
  switch (f) {
    case Format::Vdb: return "vdb";
    case Format::Raw: return "raw";
    case Format::Ktx2: return "ktx2";
    case Format::AtlasPng: return "atlas-png";
    case Format::AtlasExr: return "atlas-exr";
  }
  return "?";
}

bool needs_detail(Format f, const ExportOptions& o) { return f != Format::Vdb || o.vdb_detail; }

void atomic_write(const std::string& path, const std::function<void(const std::string&)>& fill) {
  fs::path dst(path);
  fs::path dir = dst.parent_path().empty() ? fs::path(".") : dst.parent_path();
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw IoError(path + ": cannot create folder " + dir.string());
  std::random_device rd;
  const std::string tmp = (dir / ("." + dst.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                                  std::to_string(rd() % 100000)))
                              .string();
  try {
    fill(tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, dst, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw IoError(path + ": cannot move the finished file into place: " + ec.message());
  }
}

namespace {

void write_bytes(const std::string& path, const void* data, size_t n) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), std::streamsize(n));
  out.close();
  if (!out) throw IoError(path + ": write failed (disk full or not writable?)");
}

std::vector<uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}


}  // namespace

size_t texel_bytes(const std::string& t) {
  if (t == "rgba8") return 4;
  if (t == "rgba16f") return 8;
  if (t == "rgba32f") return 16;
  throw InputError("texel format \"" + t + "\" is not one of rgba8, rgba16f, rgba32f");
}

std::vector<uint8_t> pack_texels(const Volume& v, const std::string& t) {
  const size_t n = v.voxel_count(), tb = texel_bytes(t);
  std::vector<uint8_t> out(n * tb);
  const float* ch[4] = {v.density.data(), v.detail[0].empty() ? nullptr : v.detail[0].data(),
                        v.detail[1].empty() ? nullptr : v.detail[1].data(),
                        v.detail[2].empty() ? nullptr : v.detail[2].data()};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 4; ++c) {
      const float f = ch[c] ? ch[c][i] : 0.0f;
      if (t == "rgba8") {
        out[i * 4 + c] = uint8_t(std::lround(std::clamp(f, 0.0f, 1.0f) * 255.0f));
      } else if (t == "rgba16f") {
        const uint16_t h = Imath::half(f).bits();
        std::memcpy(&out[i * 8 + c * 2], &h, 2);
      } else {
        std::memcpy(&out[i * 16 + c * 4], &f, 4);
      }
    }
  return out;
}

namespace {

void unpack_texels(Volume& v, const uint8_t* data, const std::string& t, int channels) {
  const size_t n = v.voxel_count();
  v.density.resize(n);
  for (int c = 0; c < 3; ++c) v.detail[c].assign(c + 1 < channels ? n : 0, 0.0f);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c) {
      float f;
      if (t == "rgba8") {
        f = data[i * 4 + c] / 255.0f;
      } else if (t == "rgba16f") {
        uint16_t h;
        std::memcpy(&h, data + i * 8 + c * 2, 2);
        Imath::half hv;
        hv.setBits(h);
        f = float(hv);
      } else {
        std::memcpy(&f, data + i * 16 + c * 4, 4);
      }
      (c == 0 ? v.density : v.detail[c - 1])[i] = f;
    }
}

std::string sidecar_of(const std::string& raw) { return (fs::path(raw).replace_extension(".json")).string(); }
std::string occupancy_of(const std::string& raw) {
  return (fs::path(raw).replace_extension("").string() + ".occupancy.raw");
}

json describe_json(const Volume& v, const std::string& texel) {
  json j;
  j["size"] = {v.dims[0], v.dims[1], v.dims[2]};
  j["format"] = texel;
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

}  // namespace

void write_raw(const Volume& v, const std::string& path, const ExportOptions& o) {
  const std::vector<uint8_t> texels = pack_texels(v, o.texel);
  json j = describe_json(v, o.texel);
  j["file"] = fs::path(path).filename().string();
  if (!v.occupancy.empty()) {
    const std::string occ = occupancy_of(path);
    j["occupancy"] = {{"file", fs::path(occ).filename().string()},
                      {"size", {v.occupancy_dims[0], v.occupancy_dims[1], v.occupancy_dims[2]}},
                      {"format", "r8 (0 empty, 1 occupied)"},
                      {"cell", v.occupancy_cell},
                      {"padding", v.occupancy_padding}};
    atomic_write(occ, [&](const std::string& tmp) { write_bytes(tmp, v.occupancy.data(), v.occupancy.size()); });
  }
  atomic_write(path, [&](const std::string& tmp) { write_bytes(tmp, texels.data(), texels.size()); });
  // The sidecar last: its presence means the texels and occupancy are complete.
  atomic_write(sidecar_of(path), [&](const std::string& tmp) {
    std::string s = j.dump(2) + "\n";
    write_bytes(tmp, s.data(), s.size());
  });
}

Volume read_raw(const std::string& path_in) {
  std::string raw = path_in, side = path_in;
  if (fs::path(path_in).extension() == ".json") raw = (fs::path(path_in).replace_extension(".raw")).string();
  else side = sidecar_of(path_in);
  if (!fs::exists(side)) throw InputError(raw + ": missing sidecar " + side + " (size and format live there)");
  json j;
  try {
    std::ifstream in(side);
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(side + ": not valid JSON: " + e.what());
  }
  if (!j.contains("format") || !j.contains("size"))
    throw InputError(side + ": not a cloudgen texture sidecar (no \"format\"/\"size\"; a `cloudgen noise` cube is a "
                            "single float channel, not a cloud texture)");
  Volume v;
  const std::string texel = j["format"].get<std::string>();
  for (int a = 0; a < 3; ++a) v.dims[a] = j["size"][a].get<uint32_t>();
  v.voxel_size = j.value("voxel_size", 1.0);
  if (j.contains("origin"))
    for (int a = 0; a < 3; ++a) v.origin[a] = j["origin"][a].get<double>();
  v.tiles_xz = j.value("tiles_xz", false);
  const std::vector<uint8_t> bytes = read_bytes(raw);
  const size_t want = v.voxel_count() * texel_bytes(texel);
  if (bytes.size() != want)
    throw InputError(raw + ": holds " + std::to_string(bytes.size()) + " bytes but the sidecar's size " +
                     std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) +
                     " " + texel + " needs " + std::to_string(want));
  int channels = 1;
  if (j.contains("channels"))
    for (const char* c : {"g", "b", "a"})
      if (!j["channels"].value(c, std::string()).empty()) channels = std::string("rgba").find(c[0]) + 1;
  unpack_texels(v, bytes.data(), texel, channels);
  if (j.contains("metadata"))
    for (auto& [k, val] : j["metadata"].items()) v.metadata.push_back({k, val.is_string() ? val.get<std::string>() : val.dump()});
  if (j.contains("occupancy")) {
    v.occupancy_cell = j["occupancy"].value("cell", 8u);
    v.occupancy_padding = j["occupancy"].value("padding", 2u);
  }
  build_occupancy(v);  // cheap, and guaranteed consistent with the density we just read
  return v;
}

// ---------------------------------------------------------------------------------------------
// KTX2 (Khronos Texture 2.0): one 3D image, one mip level, no supercompression.
namespace {

constexpr uint8_t kKtx2Id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};

struct Ktx2Format {
  uint32_t vk, type_size;
};
Ktx2Format ktx_format(const std::string& t) {
  if (t == "rgba8") return {37, 1};    // VK_FORMAT_R8G8B8A8_UNORM
  if (t == "rgba16f") return {97, 2};  // VK_FORMAT_R16G16B16A16_SFLOAT
  return {109, 4};                     // VK_FORMAT_R32G32B32A32_SFLOAT
}

template <class T>
void put(std::vector<uint8_t>& b, T v) {
  uint8_t tmp[sizeof(T)];
  std::memcpy(tmp, &v, sizeof(T));
  b.insert(b.end(), tmp, tmp + sizeof(T));
}
template <class T>
T get(const std::vector<uint8_t>& b, size_t off) {
  T v;
  std::memcpy(&v, b.data() + off, sizeof(T));
  return v;
}

// Khronos Data Format Descriptor, basic block, 4 samples (R, G, B, A), linear transfer.
std::vector<uint8_t> ktx_dfd(const std::string& t) {
  const uint32_t bytes = uint32_t(texel_bytes(t)), bits = bytes * 2;  // bits per channel
  const bool is_float = t != "rgba8";
  std::vector<uint8_t> d;
  const uint32_t block = 24 + 16 * 4;
  put<uint32_t>(d, 4 + block);                  // dfdTotalSize
  put<uint32_t>(d, 0);                          // vendorId 0 (Khronos), descriptorType 0 (basic)
  put<uint32_t>(d, 2u | (block << 16));         // versionNumber 2, descriptorBlockSize
  put<uint32_t>(d, 1u | (1u << 8) | (1u << 16));  // RGBSDA model, BT.709 primaries, linear transfer, straight alpha
  put<uint32_t>(d, 0);                          // texel block 1x1x1x1
  put<uint32_t>(d, bytes);                      // bytesPlane0
  put<uint32_t>(d, 0);                          // bytesPlane4..7
  const uint8_t ids[4] = {0, 1, 2, 15};
  for (int c = 0; c < 4; ++c) {
    uint32_t type = ids[c] | (is_float ? 0x80u | 0x40u : 0u);
    put<uint32_t>(d, (c * bits) | ((bits - 1) << 16) | (type << 24));
    put<uint32_t>(d, 0);  // sample position
    if (is_float) {
      put<uint32_t>(d, 0xBF800000u);  // -1.0f
      put<uint32_t>(d, 0x3F800000u);  // 1.0f
    } else {
      put<uint32_t>(d, 0);
      put<uint32_t>(d, 255);
    }
  }
  return d;
}

}  // namespace

void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o) {
  const std::vector<uint8_t> texels = pack_texels(v, o.texel);
  const Ktx2Format f = ktx_format(o.texel);
  const std::vector<uint8_t> dfd = ktx_dfd(o.texel);
  std::vector<uint8_t> kvd;
  {
    const std::string key = "KTXwriter", val = std::string("cloudgen ") + CLOUDGEN_VERSION;
    const uint32_t len = uint32_t(key.size() + 1 + val.size() + 1);
    put<uint32_t>(kvd, len);
    kvd.insert(kvd.end(), key.begin(), key.end());
    kvd.push_back(0);
    kvd.insert(kvd.end(), val.begin(), val.end());
    kvd.push_back(0);
    while (kvd.size() % 4) kvd.push_back(0);
  }
  const uint32_t header = 80 + 24;  // header + index + one level entry
  const uint32_t dfd_off = header, kvd_off = dfd_off + uint32_t(dfd.size());
  uint64_t data_off = kvd_off + kvd.size();
  const uint64_t align = std::max<uint64_t>(4, texel_bytes(o.texel));
  data_off = (data_off + align - 1) / align * align;
  std::vector<uint8_t> b(kKtx2Id, kKtx2Id + 12);
  put<uint32_t>(b, f.vk);
  put<uint32_t>(b, f.type_size);
  put<uint32_t>(b, v.dims[0]);
  put<uint32_t>(b, v.dims[1]);
  put<uint32_t>(b, v.dims[2]);
  put<uint32_t>(b, 0);  // layerCount
  put<uint32_t>(b, 1);  // faceCount
  put<uint32_t>(b, 1);  // levelCount
  put<uint32_t>(b, 0);  // supercompressionScheme
  put<uint32_t>(b, dfd_off);
  put<uint32_t>(b, uint32_t(dfd.size()));
  put<uint32_t>(b, kvd_off);
  put<uint32_t>(b, uint32_t(kvd.size()));
  put<uint64_t>(b, 0);  // sgd
  put<uint64_t>(b, 0);
  put<uint64_t>(b, data_off);
  put<uint64_t>(b, texels.size());
  put<uint64_t>(b, texels.size());
  b.insert(b.end(), dfd.begin(), dfd.end());
  b.insert(b.end(), kvd.begin(), kvd.end());
  b.resize(data_off, 0);
  b.insert(b.end(), texels.begin(), texels.end());
  atomic_write(path, [&](const std::string& tmp) { write_bytes(tmp, b.data(), b.size()); });
}

Volume read_ktx2(const std::string& path) {
  const std::vector<uint8_t> b = read_bytes(path);
  if (b.size() < 104 || std::memcmp(b.data(), kKtx2Id, 12) != 0) throw InputError(path + ": not a KTX2 file");
  const uint32_t vk = get<uint32_t>(b, 12);
  std::string texel = vk == 37 ? "rgba8" : vk == 97 ? "rgba16f" : vk == 109 ? "rgba32f" : "";
  if (texel.empty()) throw InputError(path + ": KTX2 vkFormat " + std::to_string(vk) + " is not RGBA8/RGBA16F/RGBA32F");
  Volume v;
  for (int a = 0; a < 3; ++a) v.dims[a] = std::max<uint32_t>(1, get<uint32_t>(b, 20 + 4 * a));
  if (get<uint32_t>(b, 44) != 0) throw InputError(path + ": KTX2 supercompression is not supported");
  const uint64_t off = get<uint64_t>(b, 80), len = get<uint64_t>(b, 88);
  if (len != v.voxel_count() * texel_bytes(texel) || off + len > b.size())
    throw InputError(path + ": KTX2 level size does not match " + std::to_string(v.dims[0]) + "x" +
                     std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]));
  unpack_texels(v, b.data() + off, texel, 4);
  build_occupancy(v);
  return v;
}

// ---------------------------------------------------------------------------------------------
// Slice atlas: one tile per height level y (an x-z slice), tiles in row-major order, as Unreal's
// and Godot's 3D-texture importers expect (slice axis = the engine's up axis).
void write_atlas(const Volume& v, const std::string& path, Format f) {
  const uint32_t nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
  const uint32_t cols = uint32_t(std::ceil(std::sqrt(double(ny)))), rows = (ny + cols - 1) / cols;
  const uint32_t W = cols * nx, H = rows * nz;
  const std::vector<uint8_t> t8 = f == Format::AtlasPng ? pack_texels(v, "rgba8") : std::vector<uint8_t>();
  const std::vector<uint8_t> t16 = f == Format::AtlasExr ? pack_texels(v, "rgba16f") : std::vector<uint8_t>();
  atomic_write(path, [&](const std::string& tmp) {
    if (f == Format::AtlasPng) {
      std::vector<uint8_t> img(size_t(W) * H * 4, 0);
      for (uint32_t y = 0; y < ny; ++y)
        for (uint32_t z = 0; z < nz; ++z)
          std::memcpy(&img[((size_t(y / cols) * nz + z) * W + size_t(y % cols) * nx) * 4], &t8[v.index(0, y, z) * 4],
                      size_t(nx) * 4);
      png_image im;
      std::memset(&im, 0, sizeof im);
      im.version = PNG_IMAGE_VERSION;
      im.width = W, im.height = H, im.format = PNG_FORMAT_RGBA;
      if (!png_image_write_to_file(&im, tmp.c_str(), 0, img.data(), 0, nullptr))
        throw IoError(path + ": PNG write failed: " + im.message);
    } else {
      std::vector<Imf::Rgba> img(size_t(W) * H, Imf::Rgba(0, 0, 0, 0));
      for (uint32_t y = 0; y < ny; ++y)
        for (uint32_t z = 0; z < nz; ++z)
          std::memcpy(&img[(size_t(y / cols) * nz + z) * W + size_t(y % cols) * nx], &t16[v.index(0, y, z) * 8],
                      size_t(nx) * 8);
      Imf::RgbaOutputFile out(tmp.c_str(), int(W), int(H), Imf::WRITE_RGBA);
      out.setFrameBuffer(img.data(), 1, W);
      out.writePixels(int(H));
    }
  });
  json j = describe_json(v, f == Format::AtlasPng ? "rgba8" : "rgba16f");
  j["file"] = fs::path(path).filename().string();
  j["layout"] = {{"slice_axis", "y (height): tile i holds the x-z slice at height y = i"},
                 {"tiles", {cols, rows}},
                 {"tile_size", {nx, nz}},
                 {"image_size", {W, H}},
                 {"order", "row-major, tile i at column i % tiles[0], row i / tiles[0]; pixel (x, row z)"}};
  atomic_write((fs::path(path).replace_extension(".json")).string(), [&](const std::string& tmp) {
    std::string s = j.dump(2) + "\n";
    write_bytes(tmp, s.data(), s.size());
  });
}

void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o) {
  switch (f) {
    case Format::Vdb: return write_vdb(v, path, o);
    case Format::Raw: return write_raw(v, path, o);
    case Format::Ktx2: return write_ktx2(v, path, o);
    case Format::AtlasPng:
    case Format::AtlasExr: return write_atlas(v, path, f);
  }
}

Volume read_volume(const std::string& path) {
  if (!fs::exists(path)) throw InputError(path + ": no such file");
  std::string ext = fs::path(path).extension().string();
  if (ext == ".vdb") return read_vdb(path);
  if (ext == ".ktx2") return read_ktx2(path);
  if (ext == ".raw" || ext == ".json") return read_raw(path);
  throw InputError(path + ": unknown volume type \"" + ext + "\"; expected .vdb, .raw (+ .json sidecar) or .ktx2");
}

std::string describe_file(const std::string& path) {
  if (!fs::exists(path)) throw InputError(path + ": no such file");
  if (fs::path(path).extension() == ".vdb") return describe_vdb(path);
  Volume v = read_volume(path);
  std::ostringstream o;
  o << path << "\n  size " << v.dims[0] << " x " << v.dims[1] << " x " << v.dims[2] << " voxels, voxel size "
    << v.voxel_size << " m, origin (" << v.origin[0] << ", " << v.origin[1] << ", " << v.origin[2] << ")"
    << (v.tiles_xz ? ", tiles in x and z" : "") << "\n";
  auto range = [&](const char* name, const std::vector<float>& c) {
    if (c.empty()) return;
    auto [lo, hi] = std::minmax_element(c.begin(), c.end());
    size_t active = size_t(std::count_if(c.begin(), c.end(), [](float f) { return f > 0; }));
    o << "  " << name << ": min " << *lo << ", max " << *hi << ", non-zero " << active << " ("
      << (100.0 * active / c.size()) << "%)\n";
  };
  range("R density", v.density);
  range("G detail", v.detail[0]);
  range("B detail", v.detail[1]);
  range("A detail", v.detail[2]);
  size_t occ = size_t(std::count(v.occupancy.begin(), v.occupancy.end(), uint8_t(1)));
  o << "  occupancy " << v.occupancy_dims[0] << " x " << v.occupancy_dims[1] << " x " << v.occupancy_dims[2]
    << " cells of " << v.occupancy_cell << "^3, padding " << v.occupancy_padding << ", " << occ << " occupied\n";
  for (auto& [k, val] : v.metadata) o << "  " << k << ": " << val << "\n";
  return o.str();
}

}  // namespace cloudgen
