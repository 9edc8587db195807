// Cloud motion: the parameter table (declared once: the viewer's --set motion.KEY=VALUE, cloudgen's
// sequence baking, --help and the docs all read it) and the C++ side of motion.glsl, compiled in
// double precision with glm's GLSL-named functions.
#pragma once
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "cloudgen/glsl_prelude.h"

namespace cloudgen {

/// A flow map given as an image (seed 003's flow texture): per texel the flow (up, forward) in
/// [-1, 1], from the red and green channels as `value * 2 - 1` (8 or 16 bits per channel; 0.5 is no
/// flow). x is the flow phase (it wraps: the map is one cycle, left edge after right edge; texel i
/// at phase (i + 0.5) / width), y is the height fraction: the top row at the top of the layer, the
/// bottom row at its base (row j at h = 1 - j / (height - 1)). Looked up bilinearly.
struct FlowMap {
  int width = 0, height = 0;
  std::vector<glm::dvec2> texels;  ///< row-major, row 0 = the image's top row
  std::string path;                ///< as the user gave it (for metadata and messages)
  uint64_t fnv1a = 0;              ///< FNV-1a 64 of the channel values, recorded with baked frames
  /// The flow at (phase u, height fraction h).
  glm::dvec2 sample(double u, double h) const;
};

/// Reads a PNG flow map (RGB, RGBA or palette; 8 or 16 bits). Throws InputError naming the file and
/// what is wrong (missing, not a PNG, grey, larger than kFlowMapMaxSide texels a side).
inline constexpr int kFlowMapMaxSide = 4096;
std::shared_ptr<const FlowMap> load_flow_map(const std::string& path);
/// The procedural flow map (motion.glsl procedural_flow) as a width x height image in the layout
/// load_flow_map reads: 16-bit RGB, R = up, G = forward, B = 0.5. A start for painting one.
std::vector<uint16_t> procedural_flow_image(int width, int height);
/// Writes procedural_flow_image as a 16-bit RGB PNG to `file` (a staged temporary: OutputBatch).
/// Throws IoError with libpng's reason.
void write_flow_map_png(const std::string& file, int width, int height);

/// The curl field that distorts the detail lookup (curl_distortion.glsl): CV_CURL_SIZE^3 texels,
/// x fastest, the curl of libnoise3d's tileable potential (4 lattice cells per tile, a fixed seed),
/// each component divided by the largest one so it lies in [-1, 1]; w = 0. Built once.
const std::vector<glm::vec4>& curl_field_texels();
/// Texels per side of that field: curl_distortion.glsl's CV_CURL_SIZE (static_asserted where both are seen).
inline constexpr int kCurlFieldSize = 32;
/// Texel (x, y, z) of that field, each index in [0, kCurlFieldSize): curl_distortion.glsl's
/// curl_texel for the C++ includers (the viewer's CPU reference, the sequence bake).
inline glm::dvec3 curl_field_texel(int x, int y, int z) {
  constexpr size_t n = kCurlFieldSize;
  const glm::vec4& t = curl_field_texels()[(size_t(z) * n + size_t(y)) * n + size_t(x)];
  return glm::dvec3(t.x, t.y, t.z);
}

/// Motion parameters (seed 003). The defaults move the clouds gently, so a time alone shows motion;
/// wind_speed = 0 and flow_speed = 0 (or both amplitudes 0) keep them still.
struct MotionParams {
  double wind_speed = 10.0;         ///< m/s at the cloud base
  double wind_direction = 60.0;     ///< azimuth the wind blows toward, degrees clockwise from -z
  double wind_shear = 0.5;          ///< tops move (1 + shear) times faster than bottoms
  double flow_speed = 1.0 / 120.0;  ///< flow-map cycles per second (the seed's `speed`)
  double flow_up = 120.0;           ///< flow amplitude along up at the top, m
  double flow_forward = 300.0;      ///< flow amplitude along the wind at the top, m
  double curl_amplitude = 0.0;       ///< curl distortion of the detail lookup at the base, m (0 = off)
  double curl_scale = 800.0;         ///< size of one tile of the curl field, m (whole tiles per volume)
  double curl_rise = 2.0;            ///< the curl field rises through the cloud at this speed, m/s
  /// The flow map image (`motion.flow_map=FILE.png`); null: the procedural map of motion.glsl.
  std::shared_ptr<const FlowMap> flow_map;
};

struct MotionKey {
  std::string key;
  double MotionParams::*member;
  double lo, hi;
  std::string unit;
  std::string doc;
};

/// The table: every motion.KEY with its range and meaning (defaults are MotionParams' initialisers).
const std::vector<MotionKey>& motion_keys();
/// Sets one key from text; `where` names the source for the message (e.g. "--set"). Throws
/// InputError naming the key, the value and the allowed range, or the known keys. `flow_map` takes
/// a PNG path (read now, relative to the current directory) or "procedural".
void set_motion_key(MotionParams& m, const std::string& key, const std::string& value, const std::string& where);
/// The flow_map key: its name (in set_motion_key, --help and the docs) and its value as text
/// ("procedural" or the image's path).
extern const char* const kFlowMapKey;
std::string flow_map_name(const MotionParams& m);
/// The curl field's whole repeats over a volume of `extent_m` per axis: max(1, round(extent / curl_scale)).
glm::dvec3 curl_repeats(const MotionParams& m, const glm::dvec3& extent_m);
/// How far the curl field has risen at time t, in its tiles: curl_rise * t * repeats_y / extent_y.
double curl_shift(const MotionParams& m, double t, double extent_y, double repeats_y);
/// True when any part of the motion is non-zero (a still setting skips the displacement entirely).
bool motion_moves(const MotionParams& m);
/// The box the motion measures heights in, as a volume's metadata records it (the volume header's
/// motion.box_min_y / motion.box_height, metres): true and the two values when both are present
/// and valid (finite, |min_y| <= 1e8, height > 0).
bool motion_height_box(const std::vector<std::pair<std::string, std::string>>& metadata, double& min_y,
                       double& height);
/// Records that box in `metadata` (replacing an earlier record), each value as the shortest text
/// that reads back as the same double: what motion_height_box reads.
void set_motion_height_box(std::vector<std::pair<std::string, std::string>>& metadata, double min_y, double height);
/// `--help` text and the Markdown table (docs/viewer.md, docs/motion.md).
std::string motion_help();
std::string motion_markdown();

namespace motion_glsl {
// Internal linkage: the GLSL text defines plain functions, and every includer gets its own copy.
namespace {
CV_GLSL_DOUBLE_TYPES;
CV_GLSL_BUILTINS;
#include "cloudgen/motion.glsl"
vec3 curl_texel(ivec3 i) { return curl_field_texel(i.x, i.y, i.z); }
#include "cloudgen/curl_distortion.glsl"
static_assert(CV_CURL_SIZE == kCurlFieldSize, "curl_distortion.glsl and kCurlFieldSize agree on the field size");
}  // namespace
}  // namespace motion_glsl

/// The detail lookup's curl offset in metres (curl_distortion.glsl) with the table's amplitude.
inline glm::dvec3 curl_detail_offset_m(const MotionParams& m, const glm::dvec3& uvw, double seen_h,
                                       const glm::dvec3& repeats, double shift) {
  return motion_glsl::curl_detail_offset_m(uvw, seen_h, repeats, shift, m.curl_amplitude);
}

/// D(h, t) of motion.glsl with the table's parameters (metres; see motion.glsl for the convention):
/// the procedural flow, or the flow map image looked up at the same two phases and blended alike.
inline glm::dvec3 motion_displacement(const MotionParams& m, double t, double h) {
  const glm::dvec2 wind = motion_glsl::wind_direction_xz(m.wind_direction);
  if (!m.flow_map)
    return motion_glsl::motion_displacement(t, h, wind, m.wind_speed, m.wind_shear, m.flow_speed, m.flow_up,
                                            m.flow_forward);
  const double ph = glm::clamp(h, 0.0, 1.0);
  auto offset = [&](double time) {
    const glm::dvec2 p = motion_glsl::flow_phases(time, m.flow_speed);
    return motion_glsl::flow_blend(p.x, m.flow_map->sample(p.x, ph), m.flow_map->sample(p.y, ph));
  };
  return motion_glsl::motion_displacement_of(t, ph, wind, m.wind_speed, m.wind_shear, offset(t) - offset(0.0),
                                             m.flow_up, m.flow_forward);
}

}  // namespace cloudgen
