// Writers and readers of every output format, one source file per format (raw_io.cpp, ktx2_io.cpp,
// atlas_io.cpp, vdb_io.cpp) behind this registry (formats.cpp). Every writer stages its files in an
// OutputBatch (cloudgen/output.h): nothing appears until every file of the run is complete, the
// files a run replaces are never lost, and every write is checked.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cloudgen/export_options.h"
#include "cloudgen/output.h"
#include "cloudgen/printable.h"
#include "cloudgen/volume.h"

namespace cloudgen {

enum class Format { Vdb, Raw, Ktx2, AtlasPng, AtlasExr, Nvdb };
/// "vdb", "raw", "ktx2", "atlas-png", "atlas-exr"; throws InputError naming the allowed values.
Format parse_format(const std::string& s);
/// From the extension: .vdb, .raw, .ktx2, .png (atlas-png), .exr (atlas-exr).
Format format_from_path(const std::string& path);
const char* format_name(Format f);

/// Whether writing `f` with `o` reads the detail channels (so the generator can skip them).
bool needs_detail(Format f, const ExportOptions& o);

/// Every file that writing `path` as `f` creates, the main file first, then its sidecars
/// (raw: .json and .occupancy.raw; atlases: .json), each with its role for messages.
struct OutputFile {
  std::string path, role;
};
std::vector<OutputFile> output_files(const std::string& path, Format f, bool with_occupancy);

/// Stages `path` (and its sidecars) in `batch`; the caller commits.
void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o, OutputBatch& batch);
/// Writes `path` (and its sidecars) all or nothing.
void write_volume(const Volume& v, const std::string& path, Format f, const ExportOptions& o);

// Individual formats (write_volume dispatches to these). The overloads without a batch commit at once.
void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch);
void write_vdb(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_vdb(const std::string& path, uint64_t max_bytes = kDefaultReadBudget);
/// Level of detail `level` of a .vdb (export.vdb.lod): the grids density_level_L and NAME_level_L
/// of the detail channels, with the full-resolution density's metadata and look (render.sigma_t
/// pinned to its extinction); level 0 is read_vdb. InputError naming the levels the file has.
Volume read_vdb_level(const std::string& path, uint32_t level, uint64_t max_bytes = kDefaultReadBudget);
/// How many levels of detail a .vdb holds (grids density_level_1 .. density_level_N; 0 if none).
uint32_t vdb_lod_levels(const std::string& path);
/// A float grid of a .vdb as stored (no cropping): what `cloudgen info` says of it.
struct VdbGridSummary {
  std::string name;
  double voxel_size = 0;  ///< metres
  uint64_t active_voxels = 0;
  double integral = 0;  ///< sum of the active values times the voxel volume (m^3; tiles count every voxel)
};
/// Every float grid of a .vdb, in file order.
std::vector<VdbGridSummary> vdb_grid_summaries(const std::string& path);
/// NanoVDB (.nvdb): the grids and metadata of the .vdb export as NanoVDB float grids
/// (src/io/nvdb_io.cpp; sparse access in cloudgen/nvdb.h). read_nvdb_volume densifies.
void write_nvdb(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch);
Volume read_nvdb_volume(const std::string& path, uint64_t max_bytes = kDefaultReadBudget);
void write_raw(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch);
void write_raw(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_raw(const std::string& path, uint64_t max_bytes = kDefaultReadBudget);
void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o, OutputBatch& batch);
void write_ktx2(const Volume& v, const std::string& path, const ExportOptions& o);
Volume read_ktx2(const std::string& path, uint64_t max_bytes = kDefaultReadBudget);
/// Parses a KTX2 file already in memory (`name` for messages); what read_ktx2 and the fuzzer call.
Volume parse_ktx2(const std::vector<uint8_t>& bytes, const std::string& name, uint64_t max_bytes = kDefaultReadBudget);
/// Parses a raw texture from its sidecar text and texel bytes (`name`: the .raw path, for messages;
/// the sidecar is named after it); the occupancy
/// file's bytes are optional (empty: rebuilt from the density).
Volume parse_raw(const std::string& sidecar_text, const std::vector<uint8_t>& texels, const std::string& name,
                 const std::vector<uint8_t>* occupancy_bytes = nullptr, uint64_t max_bytes = kDefaultReadBudget);

/// Throws InputError naming the channel and the count if any channel holds NaN or infinity
/// (they would render as black or white garbage).
void check_finite_channels(const Volume& v, const std::string& name);

/// Throws InputError if a dense volume of `voxels` with `channels` float channels (plus `extra`
/// bytes) needs more than `max_bytes`: "NAME: ... needs about 12.0 GiB, more than the 8.00 GiB allowed".
void check_read_budget(uint64_t voxels, int channels, uint64_t extra, uint64_t max_bytes, const std::string& name);
void write_atlas(const Volume& v, const std::string& path, Format f, OutputBatch& batch);
void write_atlas(const Volume& v, const std::string& path, Format f);

/// Human-readable description of a file cloudgen wrote (`cloudgen info`): sizes, value ranges
/// with NaN/inf counted, metadata (control characters escaped).
std::string describe_file(const std::string& path);
std::string describe_vdb(const std::string& path);

/// Packs the four channels into texels (x fastest). Detail channels absent in v are 0.
std::vector<uint8_t> pack_texels(const Volume& v, Texel t);

}  // namespace cloudgen
