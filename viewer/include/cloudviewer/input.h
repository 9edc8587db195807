// The viewer's inputs: files cloudgen reads or generates, synthetic volumes, and open_input, which
// turns any of them into a PreparedVolume.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "cloudgen/volume.h"
#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudgen {
class NoiseCache;
}

namespace cloudviewer {

/// How a preset .json INPUT is generated.
struct PresetSource {
  /// KEY=VALUE overrides of the preset's own keys, spelled as `cloudgen generate --set` spells them
  /// (threshold=0.4, coverage.low=0.2), applied in order; an InputError for any other INPUT.
  std::vector<std::string> sets;
  /// The channels' noise kept between generations (cloudviewer --edit): an edit that changes only
  /// what is applied after the noise recombines it. Null: nothing kept.
  cloudgen::NoiseCache* noise_cache = nullptr;
  /// Memory for the prepared dense channels (a prepared volume no longer drawn: Session keeps the
  /// one an edit replaced), taken by prepare_volume. Null: fresh memory.
  std::vector<float>* spare_rgba = nullptr;
};

/// Where open_input's time went (the generation's noise figures for a preset INPUT).
struct InputTiming {
  double load_s = 0;     ///< reading, or generating a preset
  double prepare_s = 0;  ///< prepare_volume / prepare_nano: occupancy grid, distance field, conversion
  size_t noise_cached = 0, noise_evaluated = 0;  ///< a preset's channel boxes (cloudgen::GenerateStats)
};

/// Loads INPUT: `synthetic:sphere|slab|blob|noise` or a file cloudgen reads / generates from.
/// Throws InputError (missing file, unknown kind, not a cloud volume, too large for the memory) with
/// the path in the message; cloudgen's IoError (the file could not be read) passes through.
cloudgen::Volume load_volume(const std::string& input, const PresetSource& preset = {}, InputTiming* timing = nullptr);

/// Synthetic volumes for development and tests (no cloudgen needed):
///  sphere: 64^3 voxels of 10 m, a soft ball with hash-noise detail channels;
///  slab:   32x8x32 voxels of 5 m, density 1 everywhere (160 x 40 x 160 m), no detail;
///  blob:   96x48x96 voxels of 12 m, fBm-shaped cumulus with height profile and detail.
cloudgen::Volume synthetic_volume(const std::string& kind);

/// The viewer's input dispatch, everything before OpenGL in one call (what main, the window, the
/// bench and a fuzz target use): load_volume then prepare_volume with the settings' occupancy grid,
/// or, when use_nanovdb says so, the NanoVDB grids (.nvdb read sparse, .vdb converted sparse,
/// other inputs converted from their dense channels) through prepare_nano.
/// Throws InputError / IoError as those do; never allocates what check_memory refuses.
/// `lod_level` > 0: that level of detail of a .vdb (cloudgen::read_vdb_level; cloudviewer/lod.h
/// chooses it), read dense and sent sparse when use_nanovdb says so; other inputs ignore it.
/// `preset`: how a preset INPUT is generated; `timing`, when given, receives where the time went.
PreparedVolume open_input(const std::string& input, const RenderSettings& s, uint32_t lod_level = 0,
                          const PresetSource& preset = {}, InputTiming* timing = nullptr);

}  // namespace cloudviewer
