// Fractal (fBm) composition, parameter validation and the point form of evaluate().
#include <algorithm>
#include <cmath>
#include <vector>
#include <string>

#include "detail.h"
#include "fractal_detail.h"
#include "noise3d/noise3d.h"

namespace noise3d {

const char* version() { return "0.1.0"; }

const char* kind_name(Kind k) {
  switch (k) {
    case Kind::Perlin: return "perlin";
    case Kind::Worley: return "worley";
    case Kind::PerlinWorley: return "perlin-worley";
  }
  return "?";
}

Kind parse_kind(const std::string& s) {
  if (s == "perlin") return Kind::Perlin;
  if (s == "worley") return Kind::Worley;
  if (s == "perlin-worley") return Kind::PerlinWorley;
  throw InvalidParameter("kind", "must be one of perlin, worley, perlin-worley; got \"" + s + "\"");
}

std::array<double, 2> value_range(Kind k) {
  return k == Kind::Perlin ? std::array<double, 2>{-1.0, 1.0} : std::array<double, 2>{0.0, 1.0};
}

void validate(const FractalParams& p) {
  detail::check_period(p.period);
  if (p.octaves < 1 || p.octaves > kMaxOctaves)
    throw InvalidParameter("octaves", "must be an integer in [1, " + std::to_string(kMaxOctaves) +
                                          "], got " + std::to_string(p.octaves));
  if (p.worley_octaves < 0 || p.worley_octaves > kMaxOctaves)
    throw InvalidParameter("worley_octaves", "must be an integer in [0, " +
                                                 std::to_string(kMaxOctaves) + "], got " +
                                                 std::to_string(p.worley_octaves));
  if (!std::isfinite(p.gain) || p.gain <= 0 || p.gain > 1)
    throw InvalidParameter("gain", "must be a finite number in (0, 1], got " + std::to_string(p.gain));
  if (!(p.blend >= 0 && p.blend <= 1))
    throw InvalidParameter("blend", "must be a number in [0, 1], got " + std::to_string(p.blend));
  if (!std::isfinite(p.lacunarity) || p.lacunarity != std::floor(p.lacunarity))
    throw InvalidParameter("lacunarity",
                           "must be an integer when tiling (a non-integer lacunarity gives octave "
                           "periods that are not integers, which breaks the wrap), got " +
                               std::to_string(p.lacunarity));
  if (p.lacunarity < 2 || p.lacunarity > kMaxLacunarity)
    throw InvalidParameter("lacunarity", "must be an integer in [2, " + std::to_string(kMaxLacunarity) +
                                             "], got " + std::to_string(p.lacunarity));
  // The highest octave's period must still fit the lattice.
  const int most = std::max(p.octaves, p.worley_octaves);
  const uint32_t per[3] = {p.period.x, p.period.y, p.period.z};
  for (uint32_t v : per) {
    double top = v * std::pow(p.lacunarity, most - 1);
    if (top > kMaxPeriod)
      throw InvalidParameter("octaves", "period * lacunarity^(octaves-1) = " + std::to_string(top) +
                                            " exceeds the largest period " + std::to_string(kMaxPeriod) +
                                            "; use fewer octaves or a smaller period");
  }
}

namespace detail {

std::vector<Octave> octaves(const FractalParams& p, Kind which) {
  const int n = which == Kind::Worley && p.kind == Kind::PerlinWorley && p.worley_octaves > 0
                    ? p.worley_octaves
                    : p.octaves;
  std::vector<Octave> out;
  double amp = 1, total = 0;
  uint64_t scale = 1;
  const uint64_t lac = static_cast<uint64_t>(p.lacunarity);
  for (int o = 0; o < n; ++o) {
    Octave oc;
    oc.scale = scale;
    oc.period = {static_cast<uint32_t>(p.period.x * scale), static_cast<uint32_t>(p.period.y * scale),
                 static_cast<uint32_t>(p.period.z * scale)};
    oc.amplitude = amp;
    // Each octave (and each kind) draws an independent pattern.
    oc.seed = p.seed ^ (static_cast<uint64_t>(seed_key(p.seed, 0x0c7a0u + o + (which == Kind::Worley ? 64 : 0))) << 32);
    total += amp;
    out.push_back(oc);
    amp *= p.gain;
    scale *= lac;
  }
  const double norm = which == Kind::Perlin ? 1.0 / (kPerlinBound * total) : 1.0 / total;
  for (Octave& oc : out) oc.weight = oc.amplitude * norm;
  return out;
}

double combine_perlin_worley(double perlin_fbm, double worley_fbm, double blend) {
  double pp = 0.5 + 0.5 * perlin_fbm;
  pp = pp < 0 ? 0 : (pp > 1 ? 1 : pp);
  const double pw = worley_fbm + pp * (1.0 - worley_fbm);
  return blend == 1.0 ? pw : pp + blend * (pw - pp);
}

}  // namespace detail

namespace {

double fbm_point(const FractalParams& p, Kind which, double x, double y, double z) {
  double sum = 0;
  for (const detail::Octave& oc : detail::octaves(p, which)) {
    const double s = static_cast<double>(oc.scale);
    double v = which == Kind::Perlin ? perlin_d(x * s, y * s, z * s, oc.period, oc.seed)
                                     : 1.0 - worley(x * s, y * s, z * s, oc.period, oc.seed).f1 / kSqrt3;
    sum += oc.weight * v;
  }
  return sum;
}

}  // namespace

double evaluate(const FractalParams& p, double x, double y, double z) {
  validate(p);
  switch (p.kind) {
    case Kind::Perlin: return fbm_point(p, Kind::Perlin, x, y, z);
    case Kind::Worley: return fbm_point(p, Kind::Worley, x, y, z);
    case Kind::PerlinWorley:
      return detail::combine_perlin_worley(fbm_point(p, Kind::Perlin, x, y, z),
                                           fbm_point(p, Kind::Worley, x, y, z), p.blend);
  }
  return 0;
}

}  // namespace noise3d
