// Input dispatch, everything before OpenGL: INPUT (synthetic, a file cloudgen reads, or a preset it
// generates from) to the prepared volume both renderers sample.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/io.h"
#include "cloudgen/nvdb.h"
#include "cloudgen/view.h"
#endif

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#if __has_include("cloudgen/generate.h")
#include "cloudgen/generate.h"
#include "cloudgen/noise_cache.h"
#include "cloudgen/preset.h"
#include "cloudgen/texture_pack.h"
#define CLOUDVIEWER_HAS_GENERATE 1
#endif
#endif

namespace cloudviewer {
namespace {

std::string lower_extension(const std::string& input) {
  std::string ext = std::filesystem::path(input).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

/// Preset keys change a preset before it is generated: refused for any other input.
void refuse_preset_sets(const std::string& input, const PresetSource& preset) {
  if (preset.sets.empty()) return;
  throw InputError("--set " + preset.sets.front() + ": a preset key, but the input '" + input +
                   "' is not a preset .json (preset keys apply before a preset is generated; other inputs take "
                   "render.*, atmosphere.* and motion.* keys)");
}

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
#endif

}  // namespace

cloudgen::Volume load_volume(const std::string& input, const PresetSource& src, InputTiming* timing) {
  if (input.rfind("synthetic:", 0) == 0) {
    refuse_preset_sets(input, src);
    return synthetic_volume(input.substr(10));
  }
  std::error_code ec;
  if (!std::filesystem::exists(input, ec))
    throw InputError("input '" + input + "': no such file");
  if (std::filesystem::is_directory(input, ec))
    throw InputError("input '" + input + "': is a directory, expected a .vdb, .nvdb, .raw/.json, .ktx2 or preset .json file");
  const std::string ext = lower_extension(input);
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  // cloudgen's own errors pass through with their type: a file that cannot be read stays an I/O
  // error (exit 2), a file that is not a volume an input error (exit 1).
#ifdef CLOUDVIEWER_HAS_GENERATE
  if (ext == ".json") {
    // A texture pack's pack.json (cloudgen generate --texture-pack): its base texture, rendered by
    // the viewer's own formula; every texture of the pack and its mips are checked on the way.
    if (std::filesystem::file_size(input, ec) <= (1u << 20) && !ec) {
      const std::vector<uint8_t> text = cloudgen::read_file_bytes(input, size_t(1) << 20);
      if (cloudgen::is_pack_json(std::string(text.begin(), text.end()))) {
        refuse_preset_sets(input, src);
        return cloudgen::read_texture_pack(input);
      }
    }
    // A raw texture's sidecar is also .json: cloudgen's reader tells them apart; try it first.
    cloudgen::Volume raw;
    bool is_raw = true;
    try {
      raw = cloudgen::read_volume(input);
    } catch (const cloudgen::InputError&) {
      is_raw = false;
    }
    if (is_raw) {
      refuse_preset_sets(input, src);
      return raw;
    }
    cloudgen::Preset preset = cloudgen::load_preset(input, src.sets);
    // Refuse before generating what would not fit: cloudgen's working set plus the viewer's copy.
    const uint64_t voxels = uint64_t(preset.resolution[0]) * preset.resolution[1] * preset.resolution[2];
    check_memory("input '" + input + "' (preset, " + std::to_string(preset.resolution[0]) + "x" +
                     std::to_string(preset.resolution[1]) + "x" + std::to_string(preset.resolution[2]) + " voxels)",
                 cloudgen::memory_estimate(preset, true) + prepared_bytes(voxels));
    cloudgen::GenerateOptions go;
    go.noise_cache = src.noise_cache;
    // No occupancy grid: prepare_volume builds the viewer's, at render.occupancy_cell, with the
    // same function (the preset's cell, a different one for every shipped preset, went unused).
    go.occupancy = false;
    cloudgen::GenerateStats stats;
    cloudgen::Volume v = cloudgen::generate(preset, go, &stats);
    if (timing) timing->noise_cached = stats.noise_cached, timing->noise_evaluated = stats.noise_evaluated;
    return v;
  }
#endif
  refuse_preset_sets(input, src);
  return cloudgen::read_volume(input);
#else
  throw InputError("input '" + input + "' (" + (ext.empty() ? "no extension" : ext) +
                   "): this cloudviewer was built without the cloudgen library, so it can only open "
                   "synthetic:sphere|slab|blob|noise");
#endif
}

namespace {

std::string mib(uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; }

/// The dense path under render.dense_budget: refuses, naming the setting, what would not fit.
PreparedVolume prepare_dense(const cloudgen::Volume& v, const std::string& input, const RenderSettings& s,
                             std::vector<float>* spare = nullptr) {
  const uint64_t need = prepared_bytes(v.voxel_count());
  if (s.dense_budget > 0 && need > dense_budget_bytes(s))
    throw InputError("input '" + input + "': the dense volume (" + std::to_string(v.dims[0]) + "x" +
                     std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) + " voxels) needs " + mib(need) +
                     ", more than render.dense_budget=" + mib(dense_budget_bytes(s)) +
                     "; use render.volume=nanovdb or auto, or raise the budget");
  const int cell = occupancy_cell_for(s.occupancy_cell, v.dims[0], v.dims[1], v.dims[2]);
  return prepare_volume(v, cell, s.occupancy_padding, &s, spare);  // the field these settings need
}

}  // namespace

PreparedVolume open_input(const std::string& input, const RenderSettings& s, uint32_t lod_level,
                          const PresetSource& preset, InputTiming* timing) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  const std::string ext = lower_extension(input);
  const bool file = input.rfind("synthetic:", 0) != 0 && std::filesystem::exists(input);
  if (file && (ext == ".nvdb" || ext == ".vdb")) refuse_preset_sets(input, preset);
  auto sparse = [&](cloudgen::NanoVolume n) {
    const int cell = occupancy_cell_for(s.occupancy_cell, n.dims[0], n.dims[1], n.dims[2]);
    try {
      return prepare_nano(std::make_shared<const cloudgen::NanoVolume>(std::move(n)), cell, s.occupancy_padding);
    } catch (const InputError& e) {
      throw InputError("input '" + input + "': " + e.what());  // the file, as the dense path names it
    }
  };
  if (file && ext == ".nvdb") {
    cloudgen::NanoVolume n = cloudgen::read_nvdb(input);  // sparse either way; densified only for dense
    const uint64_t voxels = uint64_t(n.dims[0]) * n.dims[1] * n.dims[2];
    if (use_nanovdb(s, voxels)) return sparse(std::move(n));
    return prepare_dense(cloudgen::dense_from_nano(n, cloudgen::kDefaultReadBudget, input), input, s);
  }
  if (file && ext == ".vdb" && lod_level > 0) {  // a coarse level: small, read dense
    cloudgen::Volume v = cloudgen::read_vdb_level(input, lod_level);
    if (!use_nanovdb(s, v.voxel_count())) return prepare_dense(v, input, s);
    cloudgen::ExportOptions o;  // every channel as a grid, y-up: the viewer's own copy
    o.vdb_detail = true;
    o.vdb_bake_erosion = false;
    o.vdb_physical = false;
    o.vdb_up = 'y';
    return sparse(cloudgen::nano_from_volume(v, o));
  }
  if (file && ext == ".vdb") {
    // The active box from the grid's metadata first: a field beyond the budget is never densified,
    // and the choice is made once (the free memory changes as the volume loads).
    const cloudgen::SceneInfo info = cloudgen::read_scene_info(input);
    if (use_nanovdb(s, uint64_t(info.dims[0]) * info.dims[1] * info.dims[2]))
      return sparse(cloudgen::nano_from_vdb(input));
    return prepare_dense(load_volume(input), input, s);
  }
  const uint64_t budget = dense_budget_bytes(s);  // before loading, for the same reason
  auto t0 = std::chrono::steady_clock::now();
  cloudgen::Volume v = load_volume(input, preset, timing);
  if (timing) timing->load_s = seconds_since(t0), t0 = std::chrono::steady_clock::now();
  RenderSettings fixed = s;
  fixed.dense_budget = double(budget) / 1048576.0;
  PreparedVolume prepared;
  if (use_nanovdb(fixed, v.voxel_count())) {
    cloudgen::ExportOptions o;  // every channel as a grid, y-up: the viewer's own copy
    o.vdb_detail = true;
    o.vdb_bake_erosion = false;
    o.vdb_physical = false;
    o.vdb_up = 'y';
    prepared = sparse(cloudgen::nano_from_volume(v, o));
  } else {
    prepared = prepare_dense(v, input, s, preset.spare_rgba);
  }
#ifdef CLOUDVIEWER_HAS_GENERATE
  if (preset.noise_cache) preset.noise_cache->recycle(std::move(v));  // the next edit fills its memory
#endif
  if (timing) timing->prepare_s = seconds_since(t0);
  return prepared;
#else
  (void)lod_level, (void)timing;
  const cloudgen::Volume v = load_volume(input, preset);
  return prepare_volume(v, occupancy_cell_for(s.occupancy_cell, v.dims[0], v.dims[1], v.dims[2]), s.occupancy_padding, &s);
#endif
}

}  // namespace cloudviewer
