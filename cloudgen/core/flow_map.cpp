// The motion's two fields (cloudgen/motion.h): flow maps given as images (FlowMap: reading a PNG
// with libpng, the bilinear lookup, the procedural map rendered as an image) and the curl field
// that distorts the detail lookup (curl_field_texels, from libnoise3d's curl).
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/motion.h"
#include "noise3d/noise3d.h"
#include "cloudgen/volume.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/png_read.h"

namespace cloudgen {
namespace {

// A flow map is a few hundred texels a side; 4096 bounds what a mistaken file can make us allocate
// (4096^2 texels: 256 MiB of dvec2) before libpng reads a row.
constexpr int kMaxSide = kFlowMapMaxSide;

}  // namespace

glm::dvec2 FlowMap::sample(double u, double h) const {
  // Texel centres at u = (i + 0.5) / width in x (wrapping); rows at h = 1 - j / (height - 1) in y,
  // so the top row is the top of the layer and the bottom row its base, exactly (clamped beyond).
  const double x = (u - std::floor(u)) * width - 0.5;
  const double y = std::clamp((1.0 - h) * (height - 1), 0.0, double(height - 1));
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  const int x0 = (int(fx) % width + width) % width, x1 = (x0 + 1) % width;
  const int y0 = int(fy), y1 = std::min(y0 + 1, height - 1);
  const auto at = [&](int i, int j) { return texels[size_t(j) * size_t(width) + size_t(i)]; };
  return glm::mix(glm::mix(at(x0, y0), at(x1, y0), ax), glm::mix(at(x0, y1), at(x1, y1), ax), ay);
}

std::shared_ptr<const FlowMap> load_flow_map(const std::string& path) {
  const std::string what = "motion.flow_map " + path;
  // What the file may be (a regular file: no pipe, device or folder) and how much of it is read:
  // the one input layer's rule and words (cloudgen/input_scope.h), as for every other input.
  // 4096^2 RGBA at 16 bits, uncompressed, is 128 MiB; a PNG bigger than that is not a flow map.
  const std::vector<uint8_t> bytes = read_input_bytes(path, "the flow map " + path, what, size_t(1) << 28);
  if (!is_png(bytes.data(), bytes.size()))
    throw InputError(what + ": not a PNG file (a flow map is a PNG: R = up, G = forward, 0.5 = no flow)");
  const PngPixels px = decode_png(bytes.data(), bytes.size(), what, [&](const PngHeader& h) {
    if (h.width > uint32_t(kMaxSide) || h.height > uint32_t(kMaxSide))
      throw InputError(what + ": " + std::to_string(h.width) + " x " + std::to_string(h.height) +
                       " texels; a flow map may have at most " + std::to_string(kMaxSide) +
                       " a side (a few hundred is plenty: it is one flow cycle by the layer's height)");
    if (!h.colour)
      throw InputError(what + ": a grey image has one value per texel; a flow map needs two (R = up, G = forward)");
  });
  auto map = std::make_shared<FlowMap>();
  map->path = path;
  const uint32_t w = px.width, h = px.height;
  map->width = int(w), map->height = int(h);
  map->texels.resize(size_t(w) * h);
  const double full = px.depth == 16 ? 65535.0 : 255.0;
  uint64_t fnv = 1469598103934665603ull;
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      double v[2];
      for (int c = 0; c < 2; ++c) {
        const unsigned value = px.value(i, j, c);
        for (int b = 0; b < 2; ++b) fnv = (fnv ^ ((value >> (8 * b)) & 0xff)) * 1099511628211ull;
        v[c] = double(value) / full * 2.0 - 1.0;
      }
      map->texels[size_t(j) * w + i] = glm::dvec2(v[0], v[1]);
    }
  map->fnv1a = fnv;
  return map;
}

std::vector<uint16_t> procedural_flow_image(int width, int height) {
  std::vector<uint16_t> img(size_t(width) * size_t(height) * 3);
  auto q = [](double v) { return uint16_t(std::lround(std::clamp((v + 1.0) * 0.5, 0.0, 1.0) * 65535.0)); };
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      // The texel FlowMap::sample reads back: u = (i + 0.5) / width, h = 1 - j / (height - 1).
      const glm::dvec2 f = motion_glsl::procedural_flow(glm::dvec2((i + 0.5) / width, 1.0 - double(j) / (height - 1)));
      uint16_t* px = &img[(size_t(j) * size_t(width) + size_t(i)) * 3];
      px[0] = q(f.x), px[1] = q(f.y), px[2] = 32768;
    }
  return img;
}

void write_flow_map_png(const std::string& file, int width, int height) {
  const std::vector<uint16_t> img = procedural_flow_image(width, height);
  png_image im;
  std::memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  im.width = unsigned(width), im.height = unsigned(height), im.format = PNG_FORMAT_LINEAR_RGB;
  // 16-bit samples in the machine's byte order; libpng checks fwrite, fflush and fclose.
  if (!png_image_write_to_file(&im, file.c_str(), 0, img.data(), 0, nullptr))
    throw IoError(file + ": PNG write failed: " + im.message);
  png_image_free(&im);
}

}  // namespace cloudgen

// ------------------------------------------------------------------------------ the curl field
namespace cloudgen {

const std::vector<glm::vec4>& curl_field_texels() {
  static const std::vector<glm::vec4> texels = [] {
    constexpr int n = kCurlFieldSize;
    constexpr uint32_t lattice = 4;
    std::vector<glm::dvec3> c(size_t(n) * n * n);
    double peak = 0;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double s = double(lattice) / n;
          const auto v = noise3d::curl((i + 0.5) * s, (j + 0.5) * s, (k + 0.5) * s, noise3d::Period::cube(lattice),
                                       0xc011c0de5eedull);
          glm::dvec3& t = c[(size_t(k) * n + j) * n + i];
          t = glm::dvec3(v[0], v[1], v[2]);
          peak = std::max({peak, std::abs(t.x), std::abs(t.y), std::abs(t.z)});
        }
    std::vector<glm::vec4> out(c.size());
    for (size_t q = 0; q < c.size(); ++q) out[q] = glm::vec4(glm::vec3(c[q] / peak), 0.0f);
    return out;
  }();
  return texels;
}

}  // namespace cloudgen
