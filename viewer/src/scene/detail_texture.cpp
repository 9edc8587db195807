// The render-time detail texture (detail_texture.h).
#include "cloudviewer/detail_texture.h"

#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include <noise3d/noise3d.h>

namespace cloudviewer {

std::shared_ptr<const std::vector<float>> detail_texture(int size) {
  if (size < 2 || size > 1024) throw std::invalid_argument("detail_texture: size " + std::to_string(size) + " out of 2..1024");
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const std::vector<float>>> cached;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cached.find(size);
  if (it != cached.end()) return it->second;
  noise3d::FractalParams fp;
  fp.kind = noise3d::Kind::Worley;
  fp.period = noise3d::Period::cube(kDetailBaseCells);
  fp.seed = kDetailSeed;
  fp.octaves = kDetailOctaves;
  fp.gain = 0.5;
  fp.lacunarity = 2.0;
  std::vector<float> v(size_t(size) * size * size);
  const noise3d::MinMax mm = noise3d::evaluate_grid(fp, noise3d::GridRegion::whole(uint32_t(size)), v.data());
  const double range = mm.max > mm.min ? mm.max - mm.min : 1.0;
  for (float& x : v) x = float((double(x) - mm.min) / range);
  auto out = std::make_shared<const std::vector<float>>(std::move(v));
  cached.emplace(size, out);
  return out;
}

}  // namespace cloudviewer
