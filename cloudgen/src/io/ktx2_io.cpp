// KTX2 (Khronos Texture 2.0): one 3D image, one mip level, no supercompression. The volume's
// voxel size, origin, tiling, channel names and metadata travel in the key/value data under the key
// "cloudgen.volume" (a JSON object), so a KTX2 file reads back as the volume that was written.
#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>

#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/texture_pack.h"
#include "io/format_internal.h"

namespace cloudgen {

using detail::json;

namespace {

constexpr uint8_t kKtx2Id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
constexpr const char* kVolumeKey = "cloudgen.volume";

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
std::vector<uint8_t> ktx_dfd(Texel t) {
  const uint32_t bytes = uint32_t(texel_bytes(t)), bits = bytes * 2;  // bits per channel
  const bool is_float = t != Texel::Rgba8;
  std::vector<uint8_t> d;
  const uint32_t block = 24 + 16 * 4;
  put<uint32_t>(d, 4 + block);                    // dfdTotalSize
  put<uint32_t>(d, 0);                            // vendorId 0 (Khronos), descriptorType 0 (basic)
  put<uint32_t>(d, 2u | (block << 16));           // versionNumber 2, descriptorBlockSize
  put<uint32_t>(d, 1u | (1u << 8) | (1u << 16));  // RGBSDA model, BT.709 primaries, linear transfer, straight alpha
  put<uint32_t>(d, 0);                            // texel block 1x1x1x1
  put<uint32_t>(d, bytes);                        // bytesPlane0
  put<uint32_t>(d, 0);                            // bytesPlane4..7
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

void put_kv(std::vector<uint8_t>& kvd, const std::string& key, const std::string& val) {
  const uint32_t len = uint32_t(key.size() + 1 + val.size() + 1);
  put<uint32_t>(kvd, len);
  kvd.insert(kvd.end(), key.begin(), key.end());
  kvd.push_back(0);
  kvd.insert(kvd.end(), val.begin(), val.end());
  kvd.push_back(0);
  while (kvd.size() % 4) kvd.push_back(0);
}

}  // namespace

void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch) {
  const std::vector<uint8_t> texels = pack_texels(v, o.texel);
  const TexelInfo& f = texel_info(o.texel);
  const std::vector<uint8_t> dfd = ktx_dfd(o.texel);
  json vol = detail::describe_json(v, o.texel);
  vol.erase("size");
  vol.erase("format");
  std::vector<uint8_t> kvd;  // keys sorted by their bytes, as KTX2 requires ('K' < 'c')
  put_kv(kvd, "KTXwriter", std::string("cloudgen ") + CLOUDGEN_VERSION);
  put_kv(kvd, kVolumeKey, vol.dump(-1, ' ', false, json::error_handler_t::replace));
  const uint32_t header = 80 + 24;  // header + index + one level entry
  const uint32_t dfd_off = header, kvd_off = dfd_off + uint32_t(dfd.size());
  uint64_t data_off = kvd_off + kvd.size();
  const uint64_t align = std::max<uint64_t>(4, f.bytes);
  data_off = (data_off + align - 1) / align * align;
  std::vector<uint8_t> b(kKtx2Id, kKtx2Id + 12);
  put<uint32_t>(b, f.vk_format);
  put<uint32_t>(b, f.channel_bytes);
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
  batch.stage(path, [&](const std::string& tmp) { write_file_bytes(tmp, b.data(), b.size()); });
}

Volume parse_ktx2(const std::vector<uint8_t>& b, const std::string& name, uint64_t max_bytes) {
  const std::string where = printable(name);
  if (b.size() < 104 || std::memcmp(b.data(), kKtx2Id, 12) != 0) throw InputError(where + ": not a KTX2 file");
  const uint32_t vk = get<uint32_t>(b, 12);
  Texel texel;
  if (!texel_from_vk(vk, &texel))
    throw InputError(where + ": KTX2 vkFormat " + std::to_string(vk) +
                     " is not one of RGBA8_UNORM (37), RGBA16_SFLOAT (97), RGBA32_SFLOAT (109)");
  Volume v;
  for (int a = 0; a < 3; ++a) {
    const uint32_t d = get<uint32_t>(b, 20 + 4 * a);
    if (d < 1 || d > detail::kMaxEdge)
      throw InputError(where + ": KTX2 pixel" + std::string(a == 0 ? "Width" : a == 1 ? "Height" : "Depth") + " " +
                       std::to_string(d) + " is outside [1, " + std::to_string(detail::kMaxEdge) +
                       "] (a cloud texture is 3D)");
    v.dims[a] = d;
  }
  if (get<uint32_t>(b, 32) != 0) throw InputError(where + ": KTX2 texture arrays (layerCount > 0) are not supported");
  if (get<uint32_t>(b, 36) != 1) throw InputError(where + ": KTX2 cube maps (faceCount != 1) are not supported");
  if (get<uint32_t>(b, 40) < 1) throw InputError(where + ": KTX2 levelCount 0 (mips to be generated) is not supported");
  if (get<uint32_t>(b, 44) != 0) throw InputError(where + ": KTX2 supercompression is not supported");
  uint64_t voxels = 0;
  if (!detail::checked_volume(v.dims[0], v.dims[1], v.dims[2], detail::kMaxVoxels, &voxels))
    throw InputError(where + ": KTX2 size holds more than 2^34 voxels");
  const uint64_t off = get<uint64_t>(b, 80), len = get<uint64_t>(b, 88);
  const uint64_t want = voxels * texel_bytes(texel);
  if (len != want || off > b.size() || len > b.size() - off)
    throw InputError(where + ": KTX2 level 0 (" + std::to_string(len) + " bytes at offset " + std::to_string(off) +
                     ") does not hold " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" +
                     std::to_string(v.dims[2]) + " " + texel_name(texel) + " texels inside the file's " +
                     std::to_string(b.size()) + " bytes");
  check_read_budget(voxels, 4, 0, max_bytes, name);
  detail::unpack_texels(v, b.data() + off, texel, 4);
  check_finite_channels(v, name);
  // Key/value data: optional; a file from another tool simply has no "cloudgen.volume".
  const uint64_t kvd_off = get<uint32_t>(b, 56), kvd_len = get<uint32_t>(b, 60);
  if (kvd_len && kvd_off <= b.size() && kvd_len <= b.size() - kvd_off) {
    for (uint64_t p = kvd_off, end = kvd_off + kvd_len; p + 4 <= end;) {
      const uint32_t n = get<uint32_t>(b, size_t(p));
      if (n > end - p - 4) throw InputError(where + ": KTX2 key/value entry at byte " + std::to_string(p) + " runs past its block");
      const char* kv = reinterpret_cast<const char*>(b.data() + p + 4);
      const char* nul = static_cast<const char*>(std::memchr(kv, 0, n));
      if (nul && std::string(kv, nul) == kVolumeKey) {
        std::string val(nul + 1, kv + n);
        while (!val.empty() && val.back() == '\0') val.pop_back();
        const json j = parse_json_checked(val, where + ": KTX2 key \"" + std::string(kVolumeKey) + "\"");
        if (!j.is_object()) throw InputError(where + ": KTX2 key \"" + kVolumeKey + "\" does not hold a JSON object");
        const detail::FieldReader f(j, where + ": KTX2 key \"" + kVolumeKey + "\"");
        v.voxel_size = f.number("voxel_size", 1.0, 1e-9, 1e9);
        if (f.has("origin")) v.origin = f.vec3("origin", -1e12, 1e12);
        v.tiles_xz = f.boolean("tiles_xz", false);
        if (f.has("channels") && f.at("channels").is_object()) {
          const detail::FieldReader cf(f.at("channels"), where + ": KTX2 channels");
          const char* keys[] = {"g", "b", "a"};
          for (int c = 0; c < 3; ++c)
            if (cf.has(keys[c]) && cf.at(keys[c]).is_string()) {
              const std::string s = cf.string(keys[c]);
              if (s.empty()) v.detail[c].clear();  // written as absent
              else v.detail_names[c] = s;
            }
        }
        if (f.has("metadata") && f.at("metadata").is_object())
          for (auto& [k, val2] : f.at("metadata").items())
            v.metadata.push_back({k, val2.is_string() ? val2.get<std::string>() : val2.dump()});
      }
      p += 4 + ((uint64_t(n) + 3) & ~uint64_t(3));
    }
  }
  build_occupancy(v);
  return v;
}

// ---- 8-bit textures with their mip chains (texture packs, texture_pack.h) ------------------------

namespace {

constexpr uint32_t kVkUnorm8[5] = {0, 9, 16, 23, 37};  // VK_FORMAT_R8_UNORM .. R8G8B8A8_UNORM by channels

// Basic DFD of `channels` 8-bit UNORM samples (R, G, B, A), linear transfer.
std::vector<uint8_t> ktx_dfd_unorm8(int channels) {
  std::vector<uint8_t> d;
  const uint32_t block = 24 + 16 * uint32_t(channels);
  put<uint32_t>(d, 4 + block);
  put<uint32_t>(d, 0);
  put<uint32_t>(d, 2u | (block << 16));
  put<uint32_t>(d, 1u | (1u << 8) | (1u << 16));
  put<uint32_t>(d, 0);
  put<uint32_t>(d, uint32_t(channels));
  put<uint32_t>(d, 0);
  const uint8_t ids[4] = {0, 1, 2, 15};
  for (int c = 0; c < channels; ++c) {
    put<uint32_t>(d, uint32_t(c * 8) | (7u << 16) | (uint32_t(ids[c]) << 24));
    put<uint32_t>(d, 0);
    put<uint32_t>(d, 0);
    put<uint32_t>(d, 255);
  }
  return d;
}

// Level data alignment: lcm(texel size, 4) (KTX2 section 3.9.7, no supercompression).
uint64_t level_alignment(int channels) { return channels == 3 ? 12 : 4; }

}  // namespace

std::vector<uint8_t> ktx2_bytes(const MipTexture& t, const std::string& volume_json) {
  if (t.channels < 1 || t.channels > 4 || t.levels.empty())
    throw std::invalid_argument("ktx2_bytes: channels 1..4 and at least one level");
  const uint32_t levels = uint32_t(t.levels.size());
  const std::vector<uint8_t> dfd = ktx_dfd_unorm8(t.channels);
  std::vector<uint8_t> kvd;
  put_kv(kvd, "KTXwriter", std::string("cloudgen ") + CLOUDGEN_VERSION);
  if (!volume_json.empty()) put_kv(kvd, kVolumeKey, volume_json);
  const uint32_t dfd_off = 80 + 24 * levels, kvd_off = dfd_off + uint32_t(dfd.size());
  const uint64_t align = level_alignment(t.channels);
  // Level data from the smallest level to the largest (the specification's order).
  std::vector<uint64_t> off(levels);
  uint64_t at = kvd_off + kvd.size();
  for (uint32_t l = levels; l-- > 0;) {
    at = (at + align - 1) / align * align;
    off[l] = at;
    at += t.levels[l].size();
  }
  std::vector<uint8_t> b(kKtx2Id, kKtx2Id + 12);
  put<uint32_t>(b, kVkUnorm8[t.channels]);
  put<uint32_t>(b, 1);  // typeSize
  put<uint32_t>(b, t.dims[0]);
  put<uint32_t>(b, t.dims[1]);
  put<uint32_t>(b, t.is_3d ? t.dims[2] : 0);
  put<uint32_t>(b, 0);  // layerCount
  put<uint32_t>(b, 1);  // faceCount
  put<uint32_t>(b, levels);
  put<uint32_t>(b, 0);  // supercompressionScheme
  put<uint32_t>(b, dfd_off);
  put<uint32_t>(b, uint32_t(dfd.size()));
  put<uint32_t>(b, kvd_off);
  put<uint32_t>(b, uint32_t(kvd.size()));
  put<uint64_t>(b, 0);
  put<uint64_t>(b, 0);
  for (uint32_t l = 0; l < levels; ++l) {
    put<uint64_t>(b, off[l]);
    put<uint64_t>(b, t.levels[l].size());
    put<uint64_t>(b, t.levels[l].size());
  }
  b.insert(b.end(), dfd.begin(), dfd.end());
  b.insert(b.end(), kvd.begin(), kvd.end());
  b.resize(at, 0);
  for (uint32_t l = 0; l < levels; ++l) std::copy(t.levels[l].begin(), t.levels[l].end(), b.begin() + off[l]);
  return b;
}

MipTexture parse_ktx2_mips(const std::vector<uint8_t>& b, const std::string& name, uint64_t max_bytes) {
  const std::string where = printable(name);
  if (b.size() < 80 || std::memcmp(b.data(), kKtx2Id, 12) != 0) throw InputError(where + ": not a KTX2 file");
  MipTexture t;
  const uint32_t vk = get<uint32_t>(b, 12);
  t.channels = 0;
  for (int c = 1; c <= 4; ++c)
    if (vk == kVkUnorm8[c]) t.channels = c;
  if (!t.channels)
    throw InputError(where + ": KTX2 vkFormat " + std::to_string(vk) +
                     " is not one of R8_UNORM (9), R8G8_UNORM (16), R8G8B8_UNORM (23), R8G8B8A8_UNORM (37)");
  if (get<uint32_t>(b, 16) != 1) throw InputError(where + ": KTX2 typeSize " + std::to_string(get<uint32_t>(b, 16)) + " is not 1 (8-bit texels)");
  const char* axis[3] = {"pixelWidth", "pixelHeight", "pixelDepth"};
  for (int a = 0; a < 3; ++a) {
    const uint32_t d = get<uint32_t>(b, 20 + 4 * a);
    if (a == 2 && d == 0) {
      t.is_3d = false;
      t.dims[2] = 1;
      continue;
    }
    if (d < 1 || d > detail::kMaxEdge)
      throw InputError(where + ": KTX2 " + axis[a] + " " + std::to_string(d) + " is outside [1, " +
                       std::to_string(detail::kMaxEdge) + "]" + (a == 2 ? " (or 0 for a 2D texture)" : ""));
    t.dims[a] = d;
  }
  if (get<uint32_t>(b, 32) != 0) throw InputError(where + ": KTX2 texture arrays (layerCount > 0) are not supported");
  if (get<uint32_t>(b, 36) != 1) throw InputError(where + ": KTX2 cube maps (faceCount != 1) are not supported");
  if (get<uint32_t>(b, 44) != 0) throw InputError(where + ": KTX2 supercompression is not supported");
  const uint32_t levels = get<uint32_t>(b, 40), most = full_mip_count(t.dims);
  if (levels < 1 || levels > most)
    throw InputError(where + ": KTX2 levelCount " + std::to_string(levels) + " is outside [1, " + std::to_string(most) +
                     "] for a " + std::to_string(t.dims[0]) + "x" + std::to_string(t.dims[1]) + "x" +
                     std::to_string(t.dims[2]) + " texture");
  if (b.size() < 80 + 24 * uint64_t(levels))
    throw InputError(where + ": KTX2 level index of " + std::to_string(levels) + " levels runs past the file's " +
                     std::to_string(b.size()) + " bytes");
  uint64_t voxels = 0;
  if (!detail::checked_volume(t.dims[0], t.dims[1], t.dims[2], detail::kMaxVoxels, &voxels) ||
      voxels * uint64_t(t.channels) > max_bytes)
    throw InputError(where + ": KTX2 level 0 holds more texel bytes than the " + std::to_string(max_bytes) + " allowed");
  const uint64_t align = level_alignment(t.channels);
  for (uint32_t l = 0; l < levels; ++l) {
    const std::array<uint32_t, 3> d = mip_dims(t.dims, l);
    const uint64_t want = uint64_t(d[0]) * d[1] * d[2] * uint64_t(t.channels);
    const size_t e = 80 + 24 * size_t(l);
    const uint64_t off = get<uint64_t>(b, e), len = get<uint64_t>(b, e + 8), ulen = get<uint64_t>(b, e + 16);
    if (len != want || ulen != want || off % align != 0 || off > b.size() || len > b.size() - off)
      throw InputError(where + ": KTX2 level " + std::to_string(l) + " (byteLength " + std::to_string(len) +
                       ", uncompressedByteLength " + std::to_string(ulen) + " at byteOffset " + std::to_string(off) +
                       ") does not hold the " + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" +
                       std::to_string(d[2]) + " level's " + std::to_string(want) + " bytes, aligned to " +
                       std::to_string(align) + ", inside the file's " + std::to_string(b.size()) + " bytes");
    t.levels.emplace_back(b.begin() + off, b.begin() + off + len);
  }
  return t;
}

Volume read_ktx2(const std::string& path, uint64_t max_bytes) {
  return parse_ktx2(read_file_bytes(path, size_t(std::min<uint64_t>(max_bytes, uint64_t(1) << 40))), path, max_bytes);
}

}  // namespace cloudgen
