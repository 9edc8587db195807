// Game-engine texture pack (`cloudgen generate ... --texture-pack DIR`, docs/textures.md): the
// Nubis layout of Schneider 2015/2017, made from a preset. Four 8-bit textures, each with its full
// mip chain, as KTX2 and as raw bytes, and a pack.json that names each texture's role, size,
// format, period in metres and how the viewer combines them:
//   base    3D RGBA8, the preset at 128 voxels on its longest axis: R the shaped density (the
//           Perlin-Worley channel after height profile, towers, coverage and threshold), G/B/A the
//           preset's Worley detail octaves (what erosion.glsl erodes R with)
//   detail  3D RGB8 32^3, tileable Worley fBm: R the viewer's render.detail texture, G and B
//           single Worley octaves at 8 and 16 cells a tile
//   curl    2D RGB8 128^2, tileable curl of Perlin noise (libnoise3d curl), x/y/z mapped to [0, 1]
//   weather 2D RGB8, R coverage, G cloud type, B top height (as `cloudgen weather-map`)
// Mips are 2x box filters (rounded to nearest).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cloudgen/output.h"
#include "cloudgen/preset.h"
#include "cloudgen/volume.h"

namespace cloudgen {

/// An 8-bit texture with its mip chain: levels[0] is the full size, each next level half as large
/// (at least 1) on every axis, down to 1 texel. Texels x fastest, `channels` bytes each.
struct MipTexture {
  std::array<uint32_t, 3> dims{{1, 1, 1}};  ///< depth 1 for a 2D texture
  bool is_3d = true;
  int channels = 4;                  ///< 1..4 (R8, RG8, RGB8, RGBA8 UNORM)
  std::array<bool, 3> wrap{{false, false, false}};  ///< axes that tile (the sampler's repeat, in pack.json)
  std::vector<std::vector<uint8_t>> levels;
};

/// Number of levels of a full chain for `dims`: floor(log2(largest edge)) + 1.
uint32_t full_mip_count(const std::array<uint32_t, 3>& dims);
/// Size of level `l` of a texture of size `dims`: max(1, dims >> l) per axis.
std::array<uint32_t, 3> mip_dims(const std::array<uint32_t, 3>& dims, uint32_t level);
/// The 2x box filter of `src` (size `dims`, `channels` bytes a texel): texel i of the result is the
/// mean of source texels 2i and 2i + 1 on every axis longer than 1 (never across an edge: the pairs
/// lie inside, so wrapping and clamping agree; an odd edge drops its last texel, as size >> 1 says),
/// rounded to nearest.
std::vector<uint8_t> box_downsample(const std::vector<uint8_t>& src, const std::array<uint32_t, 3>& dims, int channels);
/// Fills t.levels[1..] from t.levels[0] with box_downsample down to 1 texel.
void build_mips(MipTexture& t);

/// KTX2 with every level of `t` (VK_FORMAT_R8.._UNORM, level index largest first, level data
/// stored smallest first as the specification orders it). `volume_json`: optional key/value
/// "cloudgen.volume" (the JSON object write_ktx2 stores), so read_ktx2 reads level 0 as a volume.
std::vector<uint8_t> ktx2_bytes(const MipTexture& t, const std::string& volume_json = "");
/// Reads any 8-bit UNORM KTX2 (1-4 channels, 2D or 3D) with all its levels, checking every size,
/// offset and length against the file (untrusted input): InputError naming `name`, the field and
/// the value. `max_bytes` bounds the texel bytes.
MipTexture parse_ktx2_mips(const std::vector<uint8_t>& bytes, const std::string& name,
                           uint64_t max_bytes = uint64_t(1) << 32);

/// The four textures of a preset's pack (deterministic for any thread count).
struct TexturePack {
  MipTexture base, detail, curl, weather;
  Volume base_volume;  ///< the generated volume the base texture was packed from (float channels)
  Preset preset;       ///< the preset at the base texture's resolution
};
TexturePack make_texture_pack(const Preset& p, int threads = 0);

/// Every file a pack writes into `dir`, pack.json last.
std::vector<std::string> texture_pack_files(const std::string& dir);
/// Checks `dir` can hold a pack (absent, or a folder; not a file): InputError otherwise. An existing
/// folder receives the pack's files (each replaced atomically, all or none, by the batch); an absent
/// one is announced to `batch` (OutputBatch::new_folder), which creates it whole at its commit, so
/// a failed or killed run leaves no folder. Returns whether the folder is new.
bool prepare_texture_pack_dir(const std::string& dir, OutputBatch& batch);
/// Stages every file of the pack (KTX2, raw, pack.json) in `batch`.
void stage_texture_pack(const TexturePack& pack, const std::string& dir, const std::string& preset_path,
                        OutputBatch& batch);

/// What a pack.json says, validated (every field named in errors with its value and range).
struct PackTexture {
  std::string role, ktx2, raw;
  std::array<uint32_t, 3> dims{{1, 1, 1}};
  bool is_3d = true;
  int channels = 4;
  uint32_t mips = 1;
  std::array<double, 3> period_m{{0, 0, 0}};
};
struct PackDescription {
  std::string preset, preset_hash;
  std::array<double, 3> extent_m{{0, 0, 0}};
  std::vector<PackTexture> textures;  ///< base, detail, curl, weather
};
/// Parses and validates pack.json text (`where`: the file, for messages).
PackDescription parse_pack_json(const std::string& text, const std::string& where);
/// True if `text` looks like a pack.json ({"format": "cloudgen-texture-pack", ...}); never throws.
bool is_pack_json(const std::string& text);
/// If `path` holds a pack.json (read and validated), the path of its base KTX2 (which carries the
/// volume's voxel size, origin, view and look, for cloudgen::read_scene_info); otherwise "".
std::string texture_pack_base(const std::string& path);
/// Reads a pack: pack.json, then every KTX2 it names with all mips (sizes and formats as declared,
/// each mip the box filter of the level above), and returns the base texture as a volume (density
/// = R, detail = G/B/A, with the voxel size, origin and look the base KTX2 carries), which the
/// viewer renders with its own formula (medium.glsl cloud_density_seen).
Volume read_texture_pack(const std::string& pack_json_path, uint64_t max_bytes = uint64_t(1) << 32);

}  // namespace cloudgen
