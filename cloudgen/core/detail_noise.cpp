#include "cloudgen/detail_noise.h"

#include "noise3d/noise3d.h"

namespace cloudgen {

std::vector<float> stretched_worley_fbm(uint32_t edge, uint32_t cells, uint32_t octaves, uint64_t seed) {
  noise3d::FractalParams fp;
  fp.kind = noise3d::Kind::Worley;
  fp.period = noise3d::Period::cube(cells);
  fp.seed = seed;
  fp.octaves = octaves;
  fp.gain = 0.5;
  fp.lacunarity = 2.0;
  std::vector<float> v(size_t(edge) * edge * edge);
  const noise3d::MinMax mm = noise3d::evaluate_grid(fp, noise3d::GridRegion::whole(edge), v.data());
  const double range = mm.max > mm.min ? mm.max - mm.min : 1.0;
  for (float& x : v) x = float((double(x) - mm.min) / range);
  return v;
}

}  // namespace cloudgen
