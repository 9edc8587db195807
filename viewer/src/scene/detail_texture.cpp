// The render-time detail texture (detail_texture.h).
#include "cloudviewer/detail_texture.h"

#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace cloudviewer {

std::shared_ptr<const std::vector<float>> detail_texture(int size) {
  if (size < 2 || size > 1024) throw std::invalid_argument("detail_texture: size " + std::to_string(size) + " out of 2..1024");
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const std::vector<float>>> cached;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cached.find(size);
  if (it != cached.end()) return it->second;
  std::vector<float> v = cloudgen::stretched_worley_fbm(uint32_t(size), kDetailBaseCells, kDetailOctaves, kDetailSeed);
  auto out = std::make_shared<const std::vector<float>>(std::move(v));
  cached.emplace(size, out);
  return out;
}

}  // namespace cloudviewer
