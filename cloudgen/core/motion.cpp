#include "cloudgen/motion.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "cloudgen/help_text.h"
#include "cloudgen/volume.h"

namespace cloudgen {
namespace {
std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}
std::string range(const MotionKey& k) { return "[" + fmt(k.lo) + ", " + fmt(k.hi) + "]"; }
}  // namespace

const std::vector<MotionKey>& motion_keys() {
  static const std::vector<MotionKey> keys = {
      {"wind_speed", &MotionParams::wind_speed, 0, 200, "m/s", "wind speed at the cloud base (0 = no drift)"},
      {"wind_direction", &MotionParams::wind_direction, -360, 360, "deg",
       "azimuth the wind blows toward, clockwise from -z (the sun's convention)"},
      {"wind_shear", &MotionParams::wind_shear, 0, 10, "",
       "height shear: the top of the layer moves (1 + shear) times faster than its base"},
      {"flow_speed", &MotionParams::flow_speed, 0, 10, "1/s",
       "flow-map cycles per second (the flow repeats every 1/speed seconds)"},
      {"flow_up", &MotionParams::flow_up, 0, 1e5, "m",
       "flow-map amplitude along up at the top of the layer (scaled by the height fraction)"},
      {"flow_forward", &MotionParams::flow_forward, 0, 1e5, "m",
       "flow-map amplitude along the wind at the top of the layer (scaled by the height fraction)"},
      {"curl_amplitude", &MotionParams::curl_amplitude, 0, 1e4, "m",
       "curl-noise distortion of the detail lookup at the cloud base, fading to none at the top (0 = off; "
       "needs the detail channels)"},
      {"curl_scale", &MotionParams::curl_scale, 10, 1e6, "m",
       "size of one tile of the curl field (rounded so the volume holds whole tiles)"},
      {"curl_rise", &MotionParams::curl_rise, 0, 100, "m/s", "speed at which the curl field rises through the cloud"},
  };
  return keys;
}

const char* const kFlowMapKey = "flow_map";
const char* const kFlowMapDoc =
    "the flow map: \"procedural\" (the curl of a three-wave stream function) or a PNG (x = flow phase, wraps; "
    "y = height, top row = top of the layer; R = up, G = forward as value * 2 - 1); `cloudgen flowmap` writes the "
    "procedural one to paint over";

std::string flow_map_name(const MotionParams& m) { return m.flow_map ? m.flow_map->path : "procedural"; }

void set_motion_key(MotionParams& m, const std::string& key, const std::string& value, const std::string& where) {
  if (key == kFlowMapKey) {
    if (value == "procedural") {
      m.flow_map.reset();
      return;
    }
    if (value.empty()) throw InputError(where + " motion.flow_map=: give a PNG file or \"procedural\"");
    try {
      m.flow_map = load_flow_map(value);
    } catch (const InputError& e) {
      throw InputError(where + " " + e.what());
    }
    return;
  }
  for (const MotionKey& k : motion_keys()) {
    if (k.key != key) continue;
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(value.c_str(), &end);
    if (value.empty() || end != value.c_str() + value.size() || errno == ERANGE || !std::isfinite(v) || v < k.lo ||
        v > k.hi)
      throw InputError(where + " motion." + key + "=" + value + ": expected a number in " + range(k) +
                       (k.unit.empty() ? "" : " " + k.unit));
    m.*k.member = v;
    return;
  }
  std::string known;
  for (const MotionKey& k : motion_keys()) known += (known.empty() ? "" : ", ") + k.key;
  throw InputError(where + " motion." + key + ": unknown key (known: " + known + ", " + kFlowMapKey + ")");
}

bool motion_moves(const MotionParams& m) {
  return m.wind_speed > 0 || (m.flow_speed > 0 && (m.flow_up > 0 || m.flow_forward > 0)) ||
         (m.curl_amplitude > 0 && m.curl_rise > 0);
}

glm::dvec3 curl_repeats(const MotionParams& m, const glm::dvec3& extent_m) {
  glm::dvec3 r;
  for (int a = 0; a < 3; ++a) r[a] = std::max(1.0, std::round(extent_m[a] / m.curl_scale));
  return r;
}

double curl_shift(const MotionParams& m, double t, double extent_y, double repeats_y) {
  return m.curl_rise * t * repeats_y / extent_y;
}

bool motion_height_box(const std::vector<std::pair<std::string, std::string>>& metadata, double& min_y,
                       double& height) {
  bool have_min = false, have_height = false;
  for (const auto& [k, val] : metadata) {
    char* end = nullptr;
    double x = std::strtod(val.c_str(), &end);
    bool ok = !val.empty() && end == val.c_str() + val.size() && std::isfinite(x) && std::abs(x) <= 1e8;
    if (k == "motion.box_min_y" && ok) min_y = x, have_min = true;
    if (k == "motion.box_height" && ok && x > 0) height = x, have_height = true;
  }
  return have_min && have_height;
}

void set_motion_height_box(std::vector<std::pair<std::string, std::string>>& metadata, double min_y, double height) {
  auto exact = [](double x) {
    char buf[32];
    for (int prec = 6; prec <= 17; ++prec) {
      std::snprintf(buf, sizeof buf, "%.*g", prec, x);
      if (std::strtod(buf, nullptr) == x) break;
    }
    return std::string(buf);
  };
  metadata.erase(std::remove_if(metadata.begin(), metadata.end(),
                                [](const auto& kv) { return kv.first == "motion.box_min_y" || kv.first == "motion.box_height"; }),
                 metadata.end());
  metadata.push_back({"motion.box_min_y", exact(min_y)});
  metadata.push_back({"motion.box_height", exact(height)});
}

std::string motion_help() {
  MotionParams d;
  std::string s = "motion parameters (--set motion.KEY=VALUE: a flow map and the wind):\n";
  for (const MotionKey& k : motion_keys())
    s += help_entry("motion." + k.key + " " + range(k) + (k.unit.empty() ? "" : " " + k.unit) + " (default " +
                        fmt(d.*k.member) + ")",
                    k.doc);
  s += help_entry(std::string("motion.") + kFlowMapKey + " procedural | FILE.png (default procedural)", kFlowMapDoc);
  return s;
}

std::string motion_markdown() {
  MotionParams d;
  std::string md = "| key | range | unit | default | meaning |\n|---|---|---|---|---|\n";
  for (const MotionKey& k : motion_keys())
    md += "| motion." + k.key + " | " + range(k) + " | " + k.unit + " | " + fmt(d.*k.member) + " | " + k.doc + " |\n";
  md += std::string("| motion.") + kFlowMapKey + " | procedural, FILE.png |  | procedural | " + kFlowMapDoc + " |\n";
  return md;
}

}  // namespace cloudgen
