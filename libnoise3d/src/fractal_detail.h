// Octave schedule shared by the point and the batch fBm paths, so both sum the same terms.
#pragma once

#include <cstdint>
#include <vector>

#include "noise3d/noise3d.h"

namespace noise3d::detail {

struct Octave {
  uint64_t scale;    ///< lacunarity^o: multiplies base-octave coordinates
  Period period;     ///< base period * scale
  uint64_t seed;     ///< independent per octave and per kind
  double amplitude;  ///< gain^o
  double weight;     ///< amplitude with the fBm normalisation folded in
};

/// The octaves of `which` (Perlin or Worley) for params p (p already validated).
std::vector<Octave> octaves(const FractalParams& p, Kind which);
double combine_perlin_worley(double perlin_fbm, double worley_fbm, double blend);

}  // namespace noise3d::detail
