// The layer-mode coverage map (weather map): where clouds are and which type they are.
#include <algorithm>
#include <mutex>

#include "cloudviewer/constants.h"
#include "cloudviewer/scene.h"
#include "internal.h"

namespace cloudviewer {

std::shared_ptr<const std::vector<float>> procedural_coverage_map() {
  static std::mutex mutex;
  static std::shared_ptr<const std::vector<float>> cached;
  std::lock_guard<std::mutex> lock(mutex);
  if (cached) return cached;
  const int n = CV_COVERAGE_MAP_SIZE;
  std::vector<float> map(size_t(n) * n * 2, 0.f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double u = (x + 0.5) / n, v = (y + 0.5) / n;
      double c = tileable_fbm(u * 4, v * 4, 0.5, 4, 4, 21);
      double t = tileable_fbm(u * 2, v * 2, 7.5, 2, 2, 33);
      map[(size_t(y) * n + x) * 2] = float(std::clamp((c - 0.38) / 0.3, 0.0, 1.0));
      map[(size_t(y) * n + x) * 2 + 1] = float(std::clamp((t - 0.3) / 0.4, 0.0, 1.0));
    }
  cached = std::make_shared<const std::vector<float>>(std::move(map));
  return cached;
}

}  // namespace cloudviewer
