// Render settings: each parameter declared once (key, type, default, range, doc) in one table that
// drives `--set render.key=value`, `--help-params`, docs/reference/viewer-params.md and the
// window's controls (controls.h).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/motion.h"
#include "cloudviewer/atmosphere.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/mie_table.h"
#include "cloudviewer/param_table.h"

namespace cloudviewer {

// Codes stored in the shader parameters come from shaders/constants.glsl, which GLSL reads too.
enum class PhaseMode {
  None = CV_PHASE_NONE,
  HenyeyGreenstein = CV_PHASE_HG,
  Mie = CV_PHASE_MIE,
  TwoLobeHg = CV_PHASE_TWO_LOBE_HG,
  DraineHg = CV_PHASE_DRAINE_HG
};
enum class ToneMap { Reinhard = CV_TONEMAP_REINHARD, Aces = CV_TONEMAP_ACES, Clamp = CV_TONEMAP_CLAMP };
enum class OutputMode {
  Radiance = CV_OUTPUT_RADIANCE,
  Transmittance = CV_OUTPUT_TRANSMITTANCE,
  Iterations = CV_OUTPUT_ITERATIONS
};
enum class PlaceMode { Box = 0, Layer = 1 };
enum class Skipping { None = 0, Thesis = 1, Distance = 2, Tree = 3 };
enum class SkyMode { Analytic = CV_SKY_ANALYTIC, Precomputed = CV_SKY_PRECOMPUTED };
/// How the volume reaches the shaders: a dense RGBA texture, or NanoVDB grids in a GPU buffer.
enum class VolumeStorage { Auto = 0, Dense = 1, NanoVdb = 2 };
/// How the GPU finds a NanoVDB voxel: a leaf page table, or PNanoVDB's read accessor walk.
enum class NanoLookup { Table = 0, Accessor = 1, Atlas = 2 };

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
  bool occupancy = true;           ///< empty-space skipping on (false: none, whatever `skipping` says)
  Skipping skipping = Skipping::Distance;  ///< with occupancy on: thesis (one cell) or distance-field jumps
  bool occupancy_light = false;    ///< the light march also skips empty cells (no measurable gain on llvmpipe)
  bool eroded_field = true;        ///< the distance field also proves the eroded-away cells empty (docs/viewer-speed.md)
  int occupancy_cell = 2;          ///< coarse cell edge in voxels, see occupancy_cell_for (docs/viewer-speed.md)
  int occupancy_padding = 2;       ///< dilation in cells (thesis: 2; 1 is enough, see make_frame)
  bool adaptive = false;           ///< step grows with distance
  double adaptive_start = 0;       ///< m; 0 = auto (a quarter of the largest extent)
  double adaptive_growth = 0;      ///< 1/m; 0 = auto (4 / largest extent)
  bool jitter = true;              ///< jittered start against banding
  bool exact_filter = false;       ///< trilinear by hand (texelFetch) instead of the texture unit
  bool compiled_modes = true;      ///< GL: programs compiled for the frame's modes (docs/viewer-speed.md)
  bool compute = false;            ///< GL: the per-pixel cloud passes as compute shaders (the same image)
  double max_distance = 1e7;       ///< m
  double transmittance_cutoff = CV_TRANSMITTANCE_EPSILON;  ///< stop the primary march below this transmittance
  int density_step = 1;            ///< after a sample below density_step_below, step this many small steps (1: off)
  double density_step_below = 0.02;
  // medium
  double sigma_t = 0;              ///< extinction per metre at density 1; 0 = auto (0.5 / voxel size)
  double density = 1;              ///< density multiplier
  double erosion = 0.35;           ///< detail erosion strength [0,1]
  bool detail = false;             ///< render-time detail: a fine tileable Worley texture erodes the boundary (medium.glsl)
  double detail_period = 200;      ///< m: one tile of the detail texture (its finest cells are period / 16)
  double detail_strength = 0.35;   ///< its erosion strength [0, 1] (0: off, the same image bit for bit)
  int detail_size = 64;            ///< texture edge in texels (detail_texture.h)
  double albedo = 1;               ///< single-scattering albedo
  // lighting
  bool light_march = true;         ///< secondary march toward the sun
  int light_samples = 6;
  double light_step = 0;           ///< m; 0 = auto (2.5 voxels)
  double light_growth = 1.5;
  bool light_volume = true;        ///< look the sun's optical depth up in a precomputed volume (docs/viewer-speed.md)
  int light_volume_scale = 2;      ///< its texels: the volume's voxels divided by this per axis
  PhaseMode phase = PhaseMode::HenyeyGreenstein;
  double g = 0.3;                  ///< HG asymmetry (two-lobe-hg: the forward lobe's)
  double g2 = -0.3;                ///< two-lobe-hg: the backward lobe's asymmetry
  double lobe_weight = 0.97;       ///< two-lobe-hg: weight of the forward lobe
  double droplet_diameter = 20;    ///< draine-hg: droplet diameter, um
  double powder = 0.3;             ///< powder term strength [0,1]
  double powder_c = 2;             ///< c in 1 - exp(-c d)
  int ms_octaves = 4;              ///< multiple-scattering octaves (1 = single scattering; 4: docs/accuracy.md)
  double ms_attenuation = 0.5;     ///< a
  double ms_extinction = 0.5;      ///< b
  double ms_eccentricity = 0.5;    ///< c
  bool ms_volume = false;          ///< box mode: orders >= 2 from a flux-limited diffusion solve (docs/accuracy.md)
  int ms_volume_scale = 4;         ///< its cells: the volume's voxels divided by this per axis
  double sun_intensity = 30;       ///< sun radiance scale
  double ambient = 0.8;            ///< ambient sky radiance scale
  // the sun along a day (solar_sun in camera.h; the window's time-of-day slider)
  double time_of_day = -1;         ///< local solar time, hours [0, 24]; < 0 = auto (the sun of --sun, the view, the window)
  double latitude = 45;            ///< degrees, north > 0
  int day_of_year = 172;           ///< 1 = 1 January; 172 = the June solstice
  // background
  SkyMode sky = SkyMode::Precomputed;  ///< Bruneton's atmosphere, or the analytic gradient (the thesis)
  bool sky_lut = false;            ///< render.sky=precomputed: the sky from the 4D scattering LUT, not marched
  bool air_lut = true;             ///< render.sky=precomputed: the sky from the camera's air LUT, not marched
  bool ground = true;
  double ground_height = 0;        ///< m (world y)
  bool ground_height_auto = true;  ///< ground at min(0, volume bottom)
  double ground_albedo = 0.18;
  int shadow_samples = 16;
  bool shadow_map = true;          ///< box mode: the ground's cloud shadow from a precomputed 2D map (docs/viewer-speed.md)
  int shadow_map_scale = 1;        ///< its texels: this many voxels wide
  // HDR
  double exposure = 1.5;
  ToneMap tonemap = ToneMap::Reinhard;
  double bloom = 0.05;             ///< bloom strength (0 disables)
  double bloom_threshold = 1.0;
  OutputMode output = OutputMode::Radiance;
  int frame = 0;                   ///< frame index (jitter pattern, temporal cross matrix)
  bool temporal = false;           ///< temporal upsampling: 1/16 of the pixels per frame + reprojection
  double time = 0;                 ///< s: the clouds' time (`--time`; the window's clock)
  // Cloud motion (`--set motion.KEY=VALUE`; its table is cloudgen's, shared with its sequence bake).
  cloudgen::MotionParams motion;
  // volume storage (docs/nanovdb.md)
  VolumeStorage volume = VolumeStorage::Auto;  ///< auto: nanovdb when the dense texture exceeds dense_budget
  double dense_budget = 0;         ///< MiB the dense path may use (RGBA floats + occupancy); 0 = a third of the free memory
  double lod_bias = 0;             ///< .vdb levels of detail: draw levels whose voxel is at most 2^lod_bias pixels (cloudviewer/lod.h)
  NanoLookup nanovdb_lookup = NanoLookup::Atlas;  ///< GPU: brick atlas, leaf page table or PNanoVDB accessor
  // The atmosphere model (`--set atmosphere.KEY=VALUE`; its own table in atmosphere.h).
  AtmosphereSettings atmosphere;
  /// render.phase=mie's table: a --mie-table file's (read_mie_table); empty: the computed one.
  std::shared_ptr<const MiePhaseTable> mie_table;
};

/// The Mie table frames of settings `s` read: s.mie_table, or the computed one.
std::shared_ptr<const MiePhaseTable> mie_table_of(const RenderSettings& s);

/// A render.* parameter (param_table.h).
using ParamDef = Param<RenderSettings>;

/// The parameter table, in documentation order.
const std::vector<ParamDef>& render_params();
/// The entry for `key` (without "render."); throws InputError listing the known keys.
const ParamDef& render_param(const std::string& key);

/// Applies one `render.key=value` (the "render." prefix is optional), `atmosphere.key=value` or
/// `motion.key=value`.
/// Throws InputError naming the key, the value and what is allowed.
void apply_setting(RenderSettings& s, const std::string& assignment);

/// One line per parameter: "render.key=value".
std::string describe_settings(const RenderSettings& s);

/// The parameter list of docs/reference/viewer-params.md (a Markdown table: key, type, range, default, meaning),
/// generated from the table (`cloudviewer --params-markdown`; scripts/gen_docs.sh).
std::string params_markdown();

}  // namespace cloudviewer
