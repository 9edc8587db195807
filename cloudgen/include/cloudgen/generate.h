// The cloud pipeline: noise channels -> height profile -> Gaussian towers -> coverage -> threshold
// -> detail channels -> occupancy, brick by brick.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cloudgen/preset.h"
#include "cloudgen/volume.h"

namespace cloudgen {

/// Thrown when GenerateOptions::cancel becomes true (Ctrl-C in the CLI).
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

inline constexpr uint32_t kBrick = 16;  ///< bricks are 16^3 voxels aligned to the volume origin

struct GenerateOptions {
  int threads = 0;         ///< 0 = all cores; output bytes are identical for any value
  bool skip_empty = true;  ///< skip noise where density provably stays 0 (never changes a value)
  bool detail = true;      ///< compute the enabled G/B/A channels (false when no output uses them)
  bool occupancy = true;   ///< build the occupancy grid
  /// Sub-box in voxels (origin, extent; extent 0 = to the end). Values equal those of the same
  /// voxels in the full run.
  std::array<uint32_t, 3> region_origin{{0, 0, 0}};
  std::array<uint32_t, 3> region_extent{{0, 0, 0}};
  std::function<void(double fraction)> progress;  ///< called from worker threads, in [0, 1]
  const std::atomic<bool>* cancel = nullptr;
};

struct GenerateStats {
  size_t bricks = 0;           ///< bricks in the region
  size_t bricks_skipped = 0;   ///< density bricks whose noise was never evaluated
  size_t detail_bricks = 0;    ///< bricks whose detail channels were evaluated
  size_t active_voxels = 0;    ///< density > 0
  double seconds = 0;
};

/// The vertical profile (height distribution plus cloud-type gradient) at normalised height h.
double height_profile(const Preset& p, double h);
/// The Gaussian towers (explicit plus random), resolved to an explicit list.
std::vector<Tower> resolve_towers(const Preset& p);

Volume generate(const Preset& p, const GenerateOptions& opt = {}, GenerateStats* stats = nullptr);

/// Loads, validates and generates a preset file (what the viewer calls for .json inputs).
Volume generate_from_file(const std::string& preset_path, const std::vector<std::string>& set_overrides = {},
                          int threads = 0);

}  // namespace cloudgen
