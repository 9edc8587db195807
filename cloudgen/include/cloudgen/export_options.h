// How a volume is written: one struct, filled from the preset's `export.*` keys (the parameter
// table gives every default) and read by every writer. Names of each choice live in one table.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace cloudgen {

/// Texel layout of raw and KTX2 textures: four channels R, G, B, A per texel.
enum class Texel { Rgba8, Rgba16f, Rgba32f };
/// Compression of OpenVDB grids.
enum class VdbCompression { Blosc, Zip, None };
/// Value type of the grids in a .nvdb file: NanoVDB float, or one of its quantised leaf encodings
/// (per 8^3 leaf, value = min + code * (max - min) / (2^bits - 1)): 16, 8 or 4 bits a voxel, or
/// FpN, the fewest of 1, 2, 4, 8, 16 bits that keep every voxel of the leaf within a tolerance.
enum class NvdbPrecision { Float, Fp16, Fp8, Fp4, FpN };

struct TexelInfo {
  Texel texel;
  const char* name;        ///< "rgba8" ...
  uint32_t bytes;          ///< per texel (4 channels)
  uint32_t vk_format;      ///< KTX2 vkFormat (VK_FORMAT_R8G8B8A8_UNORM = 37, ...)
  uint32_t channel_bytes;  ///< KTX2 typeSize
};
const TexelInfo& texel_info(Texel t);
const char* texel_name(Texel t);
size_t texel_bytes(Texel t);
/// "rgba8" | "rgba16f" | "rgba32f"; anything else is an InputError naming `where` and the choices.
Texel parse_texel(const std::string& name, const std::string& where = "texel format");
/// The texel whose KTX2 vkFormat is `vk`, or false.
bool texel_from_vk(uint32_t vk, Texel* out);

const char* vdb_compression_name(VdbCompression c);
VdbCompression parse_vdb_compression(const std::string& name, const std::string& where = "export.vdb.compression");
/// "float" | "fp16" | "fp8" | "fp4" | "fpn": NanoVDB's own names for the grid types, lower-case.
const char* nvdb_precision_name(NvdbPrecision p);
NvdbPrecision parse_nvdb_precision(const std::string& name, const std::string& where = "export.nvdb.precision");

/// The most levels of detail `export.vdb.lod` takes (the parameter table's range).
inline constexpr uint32_t kMaxLodLevels = 16;
/// Levels of detail a volume with `dims` voxels can have: each halves the voxel count along every
/// axis, and the last one is one voxel along the longest axis (ceil(log2(longest))).
inline uint32_t max_lod_levels(const uint32_t dims[3]) {
  uint32_t longest = 1, n = 0;
  for (int a = 0; a < 3; ++a) longest = dims[a] > longest ? dims[a] : longest;
  while ((uint64_t(1) << n) < longest) ++n;
  return n;
}
/// InputError "export.vdb.lod: N levels ... allowed: 0 .. M" when `levels` exceeds max_lod_levels(dims).
void check_lod_levels(uint32_t levels, const uint32_t dims[3]);

struct ExportOptions {
  bool vdb_half = false;                                  ///< grids saved as 16-bit half floats
  uint32_t vdb_lod = 0;  ///< export.vdb.lod: coarser levels NAME_level_1 .. _N beside each grid (0 = none)
  VdbCompression vdb_compression = VdbCompression::Blosc;  ///< export.vdb.compression
  bool vdb_detail = true;                                  ///< detail channels as extra grids
  char vdb_up = 'z';              ///< 'z': height on +z (Blender), 'y': as in memory (Houdini, Maya)
  bool vdb_physical = false;      ///< density grid holds extinction per metre, not [0, 1]
  bool vdb_bake_erosion = true;   ///< density = the viewer's eroded density, no detail grids
  Texel texel = Texel::Rgba8;                              ///< raw / KTX2 texel format
  NvdbPrecision nvdb_precision = NvdbPrecision::Float;     ///< export.nvdb.precision
  /// export.nvdb.tolerance: fpn's largest absolute error per voxel, in the density grid's stored
  /// units (normalised [0, 1], or extinction per metre with export.vdb.units = physical); > 0.
  double nvdb_tolerance = 0.01;
};

}  // namespace cloudgen
