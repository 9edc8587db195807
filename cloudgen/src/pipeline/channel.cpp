// A preset's noise channel as the generator evaluates it (channel.h).
#include "cloudgen/channel.h"

#include <algorithm>
#include <cmath>

namespace cloudgen {

noise3d::FractalParams channel_params(const Preset& p, int c) {
  const Channel& ch = p.channels[c];
  noise3d::FractalParams f;
  f.kind = ch.kind;
  auto derive = [&](int axis) -> uint32_t {
    if (ch.period[axis]) return ch.period[axis];
    double v = double(ch.period[0]) * p.resolution[axis] / p.resolution[0];
    return std::max<uint32_t>(1, uint32_t(std::lround(v)));
  };
  f.period = {ch.period[0], derive(1), derive(2)};
  f.seed = p.seed + ch.seed_offset * 0x9E3779B97F4A7C15ull;
  f.octaves = ch.octaves;
  f.gain = ch.gain;
  f.lacunarity = ch.lacunarity;
  f.worley_octaves = ch.worley_octaves;
  f.blend = ch.blend;
  return f;
}

noise3d::FractalParams coverage_params(const Preset& p) {
  noise3d::FractalParams cp;
  cp.kind = p.coverage_kind;
  cp.period = {p.coverage_period, 1,
               std::max<uint32_t>(1, uint32_t(std::lround(double(p.coverage_period) * p.resolution[2] / p.resolution[0])))};
  cp.octaves = p.coverage_octaves;
  cp.seed = p.seed ^ 0xC0FEC0FEull;
  return cp;
}

float noise_to_unit(noise3d::Kind k, float v) {
  const float u = k == noise3d::Kind::Perlin ? 0.5f + 0.5f * v : v;
  return std::clamp(u, 0.0f, 1.0f);
}

float channel_value(const Channel& ch, float v) {
  float u = noise_to_unit(ch.kind, v);
  if (ch.remap[0] != 0.0 || ch.remap[1] != 1.0) {
    const float lo = float(ch.remap[0]), hi = float(ch.remap[1]);
    u = std::clamp((u - lo) / (hi - lo), 0.0f, 1.0f);
  }
  return ch.invert ? 1.0f - u : u;
}

}  // namespace cloudgen
