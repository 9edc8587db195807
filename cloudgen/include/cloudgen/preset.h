// Cloud presets: a JSON document read through one parameter table (params()) that drives defaults,
// parsing, validation, `cloudgen generate --help` and docs/presets.md.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/export_options.h"
#include "cloudgen/motion.h"
#include "cloudgen/shape.h"
#include "cloudgen/view.h"
#include "cloudgen/volume.h"
#include "noise3d/noise3d.h"

namespace cloudgen {

struct WeatherMap;  // weather_map.h

/// Largest seed: 2^53, the largest integer a JSON number holds exactly.
inline constexpr uint64_t kMaxSeed = 9007199254740992ull;

/// One noise channel of the 3D texture (R = base shape, G/B/A = detail).
struct Channel {
  bool enabled = false;
  noise3d::Kind kind = noise3d::Kind::Worley;
  std::array<uint32_t, 3> period{{4, 0, 0}};  ///< y, z of 0 = derived from x and the aspect ratio
  int octaves = 3;
  double gain = 0.5;
  int lacunarity = 2;
  int worley_octaves = 0;  ///< Perlin-Worley only; 0 = same as octaves
  double blend = 1.0;      ///< Perlin-Worley only: 1 = Perlin-Worley, 0 = Perlin alone
  bool invert = false;     ///< store 1 - v
  /// Contrast: v -> clamp((v - lo) / (hi - lo), 0, 1) on the noise in [0, 1], before invert.
  /// fBm values crowd the middle of their range (Perlin-Worley: 80% within [0.80, 0.90]).
  std::array<double, 2> remap{{0.0, 1.0}};
  uint64_t seed_offset = 0;
};

/// One Gaussian tower: a multivariate-normal peak added to the height profile. Centre and sigmas
/// are in normalised volume coordinates [0, 1]^3.
struct Tower {
  std::array<double, 3> center{{0.5, 0.2, 0.5}};
  std::array<double, 3> sigma{{0.1, 0.3, 0.1}};
  double amplitude = 0.5;
};

/// Vertical profile: the thesis's HD(h), or one of the cloud-type gradients.
enum class HeightProfile { Exponential, Stratus, Cumulus, Cumulonimbus };
const char* height_profile_name(HeightProfile h);

/// A preset. Every default comes from the parameter table: `Preset{}` equals parse_preset("{}").
struct Preset {
  Preset();  ///< the table's defaults

  std::string name = "untitled";
  std::string description;
  std::string source_path;  ///< file it was read from (for messages)
  uint64_t seed = 1;
  std::array<uint32_t, 3> resolution{{128, 128, 128}};
  double voxel_size = 10.0;
  std::array<double, 3> origin{{0, 0, 0}};
  bool tiling = true;

  std::array<Channel, 4> channels;  ///< r, g, b, a

  HeightProfile height_profile = HeightProfile::Exponential;
  double height_a = 50, height_b = 4;
  bool height_normalize = true;

  std::vector<Tower> towers;
  int tower_count = 0;  ///< extra random towers placed from tower_seed
  uint64_t tower_seed = 7;
  double tower_amplitude = 0.6;
  std::array<double, 3> tower_sigma{{0.08, 0.35, 0.08}};

  bool coverage_enabled = false;
  noise3d::Kind coverage_kind = noise3d::Kind::Perlin;
  uint32_t coverage_period = 2;
  int coverage_octaves = 3;
  double coverage_low = 0.35, coverage_high = 0.65;  ///< smoothstep edges on the noise in [0, 1]
  bool coverage_image = false;  ///< coverage.kind "image": the painted weather map (weather_map.h)
  std::string coverage_file;    ///< /coverage/file as written (weather_map holds the image)
  std::shared_ptr<const WeatherMap> weather_map;

  ShapeParams shape;  ///< the `shape` section: sources that replace profile, towers and coverage (shape.h)

  double threshold = 0.3;
  double density_scale = 1.0;

  uint32_t occupancy_cell = 4;
  uint32_t occupancy_padding = 2;

  ExportOptions export_options;  ///< export.vdb.* and export.raw.* keys

  View view;  ///< optional camera, sun and render.* settings (viewer, `cloudgen blender`, README)

  MotionParams motion;  ///< the `motion` section: wind and flow map of a baked sequence (`--frames`)
  std::string motion_flow_map = "procedural";  ///< /motion/flow_map as written (motion.flow_map holds the image)
};

/// One entry of the parameter table.
struct ParamInfo {
  std::string pointer;  ///< JSON pointer, "*" for any array index: "/towers/list/*/center"
  std::string type;     ///< "number", "integer", "bool", "string", "vec3", "ivec3", "array"
  std::string default_value;  ///< as JSON text
  std::string range;          ///< human-readable allowed values
  std::string doc;
};
const std::vector<ParamInfo>& params();

/// Markdown reference of every preset key (docs/presets.md is generated from it).
std::string params_markdown();

/// Reads and validates a preset. `overrides` are "key.path=value" strings (value parsed as JSON,
/// else taken as a string) applied before validation. Throws InputError listing every problem
/// ("<file>: /channels/r/octaves: 40 is out of range; allowed: integer in [1, 16]"); JSON syntax
/// errors give line and column; unknown keys are errors with a did-you-mean.
Preset load_preset(const std::string& path, const std::vector<std::string>& overrides = {});
Preset parse_preset(const std::string& json_text, const std::string& source_name,
                    const std::vector<std::string>& overrides = {});

/// Every problem of a preset file, empty when valid (`cloudgen validate`).
std::vector<std::string> check_preset(const std::string& path, const std::vector<std::string>& overrides = {});

/// The most voxels along an axis: the table's range of /resolution, and of --resolution (so a
/// memory estimate, at most 4096^3 voxels x 20 bytes, cannot overflow).
inline constexpr uint32_t kMaxResolution = 4096;

/// Rescales so the longest axis has n voxels, keeping proportions and world size; n outside
/// [1, kMaxResolution] is an InputError.
void rescale(Preset& p, uint32_t n);

}  // namespace cloudgen
