// Cloud motion: the parameter table (declared once: the viewer's --set motion.KEY=VALUE, cloudgen's
// sequence baking, --help and the docs all read it) and the C++ side of motion.glsl, compiled in
// double precision with glm's GLSL-named functions.
#pragma once
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace cloudgen {

/// Motion parameters (seed 003). The defaults move the clouds gently, so a time alone shows motion;
/// wind_speed = 0 and flow_speed = 0 (or both amplitudes 0) keep them still.
struct MotionParams {
  double wind_speed = 10.0;         ///< m/s at the cloud base
  double wind_direction = 60.0;     ///< azimuth the wind blows toward, degrees clockwise from -z
  double wind_shear = 0.5;          ///< tops move (1 + shear) times faster than bottoms
  double flow_speed = 1.0 / 120.0;  ///< flow-map cycles per second (the seed's `speed`)
  double flow_up = 120.0;           ///< flow amplitude along up at the top, m
  double flow_forward = 300.0;      ///< flow amplitude along the wind at the top, m
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
/// InputError naming the key, the value and the allowed range, or the known keys.
void set_motion_key(MotionParams& m, const std::string& key, const std::string& value, const std::string& where);
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
using Number = double;
using vec2 = glm::dvec2;
using vec3 = glm::dvec3;
using glm::clamp;
using glm::fract;
using glm::mix;
using std::abs;
using std::cos;
using std::sin;
#include "cloudgen/motion.glsl"
}  // namespace
}  // namespace motion_glsl

/// D(h, t) of motion.glsl with the table's parameters (metres; see motion.glsl for the convention).
inline glm::dvec3 motion_displacement(const MotionParams& m, double t, double h) {
  return motion_glsl::motion_displacement(t, h, motion_glsl::wind_direction_xz(m.wind_direction), m.wind_speed,
                                          m.wind_shear, m.flow_speed, m.flow_up, m.flow_forward);
}

}  // namespace cloudgen
