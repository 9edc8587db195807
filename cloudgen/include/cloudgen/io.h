// Writers and readers of every output format. Every writer is atomic: it writes a temporary file
// in the destination folder and renames it over the destination, so an interrupted or failed run
// never leaves a half-written output.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cloudgen/volume.h"

namespace cloudgen {

enum class Format { Vdb, Raw, Ktx2, AtlasPng, AtlasExr };
/// "vdb", "raw", "ktx2", "atlas-png", "atlas-exr"; throws InputError naming the allowed values.
Format parse_format(const std::string& s);
/// From the extension: .vdb, .raw, .ktx2, .png (atlas-png), .exr (atlas-exr).
Format format_from_path(const std::string& path);
const char* format_name(Format f);

struct ExportOptions {
  bool vdb_half = false;                  ///< grids saved as 16-bit half floats
  std::string vdb_compression = "blosc";  ///< blosc | zip | none
  bool vdb_detail = true;                 ///< detail channels as extra grids
  char vdb_up = 'z';                      ///< 'z': height on +z (Blender), 'y': as in memory (Houdini, Maya)
  bool vdb_physical = false;              ///< density grid holds extinction per metre, not [0, 1]
  bool vdb_bake_erosion = false;          ///< density = the viewer's eroded density, no detail grids
  std::string texel = "rgba8";            ///< raw / ktx2 texel format: rgba8 | rgba16f | rgba32f
};

/// Whether writing `f` with `o` reads the detail channels (so the generator can skip them).
bool needs_detail(Format f, const ExportOptions& o);

void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o);

/// Writes `path` atomically: `fill(tmp_path)` writes a temporary sibling that is renamed to
/// `path` on success and removed on failure.
void atomic_write(const std::string& path, const std::function<void(const std::string& tmp)>& fill);

// Individual formats (write_volume dispatches to these).
void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_vdb(const std::string& path);
void write_raw(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_raw(const std::string& path);
void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_ktx2(const std::string& path);
void write_atlas(const Volume& v, const std::string& path, Format f);

/// Human-readable description of a file cloudgen wrote (`cloudgen info`).
std::string describe_file(const std::string& path);
std::string describe_vdb(const std::string& path);

/// Packs the four channels into texels (x fastest). Detail channels absent in v are 0.
std::vector<uint8_t> pack_texels(const Volume& v, const std::string& texel);
size_t texel_bytes(const std::string& texel);

}  // namespace cloudgen
