// The layer-mode coverage map (weather map): where clouds are and which type they are.
#include <algorithm>
#include <mutex>

#include "cloudviewer/scene.h"
#include "internal.h"

namespace cloudviewer {

const std::vector<float>& coverage_map(int n) {
  static std::mutex mutex;
  static std::vector<float> map;
  static int cached = 0;
  std::lock_guard<std::mutex> lock(mutex);
  if (cached == n) return map;
  map.assign(size_t(n) * n * 2, 0.f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double u = (x + 0.5) / n, v = (y + 0.5) / n;
      double c = tileable_fbm(u * 4, v * 4, 0.5, 4, 4, 21);
      double t = tileable_fbm(u * 2, v * 2, 7.5, 2, 2, 33);
      map[(size_t(y) * n + x) * 2] = float(std::clamp((c - 0.38) / 0.3, 0.0, 1.0));
      map[(size_t(y) * n + x) * 2 + 1] = float(std::clamp((t - 0.3) / 0.4, 0.0, 1.0));
    }
  cached = n;
  return map;
}

}  // namespace cloudviewer
