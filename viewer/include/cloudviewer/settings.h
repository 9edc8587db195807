// Render settings: each parameter declared once (key, type, default, range, doc) in one table that
// drives `--set render.key=value`, `--help-params`, docs/viewer.md and the window's key bindings.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "cloudviewer/constants.h"

namespace cloudviewer {

// Codes stored in the shader parameters come from shaders/constants.glsl, which GLSL reads too.
enum class PhaseMode { None = CV_PHASE_NONE, HenyeyGreenstein = CV_PHASE_HG, Mie = CV_PHASE_MIE };
enum class ToneMap { Reinhard = CV_TONEMAP_REINHARD, Aces = CV_TONEMAP_ACES, Clamp = CV_TONEMAP_CLAMP };
enum class OutputMode {
  Radiance = CV_OUTPUT_RADIANCE,
  Transmittance = CV_OUTPUT_TRANSMITTANCE,
  Iterations = CV_OUTPUT_ITERATIONS
};
enum class PlaceMode { Box = 0, Layer = 1 };

struct RenderSettings {
  // placement
  PlaceMode mode = PlaceMode::Box;  ///< box: the volume where its file puts it; layer: tiled shell
  double layer_bottom = 1500;       ///< m above the ground
  double layer_top = 0;             ///< m; 0 = bottom + the texture's height in metres
  double earth_radius = 6360e3;     ///< m
  double coverage = 0;              ///< added to the coverage map [-1, 1]
  double cloud_type = -1;           ///< 0 stratus .. 0.5 cumulus .. 1 cumulonimbus; -1 = from the map
  int coverage_tiles = 8;           ///< the coverage map spans this many texture tiles
  // marching
  int steps = 128;                 ///< small steps across the volume's largest extent
  bool occupancy = true;           ///< occupancy skipping (thesis 2.4.2)
  bool occupancy_light = false;    ///< the light march also skips empty cells (no measurable gain on llvmpipe)
  int occupancy_cell = 8;          ///< coarse cell edge in voxels
  int occupancy_padding = 2;       ///< dilation in cells (thesis: 2; 1 is enough, see make_frame)
  bool adaptive = false;           ///< step grows with distance
  double adaptive_start = 0;       ///< m; 0 = auto (a quarter of the largest extent)
  double adaptive_growth = 0;      ///< 1/m; 0 = auto (4 / largest extent)
  bool jitter = true;              ///< jittered start against banding
  bool exact_filter = false;       ///< trilinear by hand (texelFetch) instead of the texture unit
  double max_distance = 1e7;       ///< m
  // medium
  double sigma_t = 0;              ///< extinction per metre at density 1; 0 = auto (0.5 / voxel size)
  double density = 1;              ///< density multiplier
  double erosion = 0.35;           ///< detail erosion strength [0,1]
  double albedo = 1;               ///< single-scattering albedo
  // lighting
  bool light_march = true;         ///< secondary march toward the sun
  int light_samples = 6;
  double light_step = 0;           ///< m; 0 = auto (2.5 voxels)
  double light_growth = 1.5;
  PhaseMode phase = PhaseMode::HenyeyGreenstein;
  double g = 0.3;                  ///< HG asymmetry
  double powder = 0.3;             ///< powder term strength [0,1]
  double powder_c = 2;             ///< c in 1 - exp(-c d)
  double sun_intensity = 30;       ///< sun radiance scale
  double ambient = 0.8;            ///< ambient sky radiance scale
  // background
  bool ground = true;
  double ground_height = 0;        ///< m (world y)
  bool ground_height_auto = true;  ///< ground at min(0, volume bottom)
  double ground_albedo = 0.18;
  int shadow_samples = 16;
  // HDR
  double exposure = 1.5;
  ToneMap tonemap = ToneMap::Reinhard;
  double bloom = 0.05;             ///< bloom strength (0 disables)
  double bloom_threshold = 1.0;
  OutputMode output = OutputMode::Radiance;
  int frame = 0;                   ///< frame index (jitter pattern)
};

struct ParamDef {
  std::string key;    ///< after "render."
  std::string type;   ///< bool, int, float, enum
  std::string range;  ///< allowed values
  std::string doc;
  std::function<void(RenderSettings&, const std::string&)> set;  ///< throws InputError
  std::function<std::string(const RenderSettings&)> get;
};

/// The parameter table, in documentation order.
const std::vector<ParamDef>& render_params();

/// Applies one `render.key=value` (the "render." prefix is optional). Throws InputError naming the
/// key, the value and what is allowed.
void apply_setting(RenderSettings& s, const std::string& assignment);

/// One line per parameter: "render.key=value".
std::string describe_settings(const RenderSettings& s);

}  // namespace cloudviewer
