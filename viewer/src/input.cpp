// Input dispatch, everything before OpenGL: INPUT (synthetic, a file cloudgen reads, or a preset it
// generates from) to the prepared volume both renderers sample.
#include <algorithm>
#include <cstdint>
#include <filesystem>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#if __has_include("cloudgen/generate.h")
#include "cloudgen/generate.h"
#include "cloudgen/preset.h"
#define CLOUDVIEWER_HAS_GENERATE 1
#endif
#endif

namespace cloudviewer {

bool has_cloudgen() {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  return true;
#else
  return false;
#endif
}

cloudgen::Volume load_volume(const std::string& input) {
  if (input.rfind("synthetic:", 0) == 0) return synthetic_volume(input.substr(10));
  std::error_code ec;
  if (!std::filesystem::exists(input, ec))
    throw InputError("input '" + input + "': no such file");
  if (std::filesystem::is_directory(input, ec))
    throw InputError("input '" + input + "': is a directory, expected a .vdb, .raw/.json, .ktx2 or preset .json file");
  std::string ext = std::filesystem::path(input).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  // cloudgen's own errors pass through with their type: a file that cannot be read stays an I/O
  // error (exit 2), a file that is not a volume an input error (exit 1).
#ifdef CLOUDVIEWER_HAS_GENERATE
  if (ext == ".json") {
    // A raw texture's sidecar is also .json: cloudgen's reader tells them apart; try it first.
    try {
      return cloudgen::read_volume(input);
    } catch (const cloudgen::InputError&) {
      cloudgen::Preset preset = cloudgen::load_preset(input);
      // Refuse before generating what would not fit: cloudgen's working set plus the viewer's copy.
      const uint64_t voxels = uint64_t(preset.resolution[0]) * preset.resolution[1] * preset.resolution[2];
      check_memory("input '" + input + "' (preset, " + std::to_string(preset.resolution[0]) + "x" +
                       std::to_string(preset.resolution[1]) + "x" + std::to_string(preset.resolution[2]) + " voxels)",
                   cloudgen::memory_estimate(preset, true) + prepared_bytes(voxels));
      return cloudgen::generate(preset);
    }
  }
#endif
  return cloudgen::read_volume(input);
#else
  throw InputError("input '" + input + "' (" + (ext.empty() ? "no extension" : ext) +
                   "): this cloudviewer was built without the cloudgen library, so it can only open "
                   "synthetic:sphere|slab|blob|noise");
#endif
}

PreparedVolume open_input(const std::string& input, const RenderSettings& s) {
  return prepare_volume(load_volume(input), s.occupancy_cell, s.occupancy_padding);
}

}  // namespace cloudviewer
