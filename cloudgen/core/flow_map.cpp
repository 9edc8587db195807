// The motion's two fields (cloudgen/motion.h): flow maps given as images (FlowMap: reading a PNG
// with libpng, the bilinear lookup, the procedural map rendered as an image) and the curl field
// that distorts the detail lookup (curl_field_texels, from libnoise3d's curl).
#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/motion.h"
#include "noise3d/noise3d.h"
#include "cloudgen/volume.h"
#include "cloudgen/input_scope.h"

namespace cloudgen {
namespace {

// A flow map is a few hundred texels a side; 4096 bounds what a mistaken file can make us allocate
// (4096^2 texels: 256 MiB of dvec2) before libpng reads a row.
constexpr int kMaxSide = kFlowMapMaxSide;

struct PngRead {
  png_structp png = nullptr;
  png_infop info = nullptr;
  FILE* file = nullptr;
  ~PngRead() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    if (file) std::fclose(file);
  }
};

// libpng reports errors through longjmp; the message is kept for the InputError thrown afterwards.
void on_error(png_structp png, png_const_charp msg) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  *text = msg ? msg : "unknown libpng error";
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

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
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(what + ": no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(what + ": not a regular file");
  protect_input(path, "the flow map " + path);
  PngRead r;
  r.file = std::fopen(path.c_str(), "rb");
  if (!r.file) throw InputError(what + ": cannot open the file");
  unsigned char sig[8] = {};
  if (std::fread(sig, 1, 8, r.file) != 8 || png_sig_cmp(sig, 0, 8) != 0)
    throw InputError(what + ": not a PNG file (a flow map is a PNG: R = up, G = forward, 0.5 = no flow)");
  // On the heap: libpng's longjmp leaves automatic objects changed after setjmp indeterminate.
  auto message = std::make_unique<std::string>();
  r.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message.get(), on_error, on_warning);
  if (!r.png) throw InputError(what + ": libpng could not start");
  r.info = png_create_info_struct(r.png);
  if (!r.info) throw InputError(what + ": libpng could not start");
  auto map = std::make_shared<FlowMap>();
  map->path = path;
  std::vector<png_byte> pixels;
  std::vector<png_bytep> rows;
  png_uint_32 w = 0, h = 0;
  int depth = 0, color = 0, channels = 0;
  if (setjmp(png_jmpbuf(r.png))) throw InputError(what + ": " + *message);
  png_init_io(r.png, r.file);
  png_set_sig_bytes(r.png, 8);
  png_read_info(r.png, r.info);
  w = png_get_image_width(r.png, r.info);
  h = png_get_image_height(r.png, r.info);
  depth = png_get_bit_depth(r.png, r.info);
  color = png_get_color_type(r.png, r.info);
  if (w > png_uint_32(kMaxSide) || h > png_uint_32(kMaxSide))
    throw InputError(what + ": " + std::to_string(w) + " x " + std::to_string(h) + " texels; a flow map may have at most " +
                     std::to_string(kMaxSide) + " a side (a few hundred is plenty: it is one flow cycle by the layer's height)");
  if (!(color & PNG_COLOR_MASK_COLOR))
    throw InputError(what + ": a grey image has one value per texel; a flow map needs two (R = up, G = forward)");
  // Values as stored: palettes expanded to RGB, no gamma or colour-space conversion.
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(r.png);
  png_read_update_info(r.png, r.info);
  channels = png_get_channels(r.png, r.info);
  depth = png_get_bit_depth(r.png, r.info);
  const size_t row_bytes = png_get_rowbytes(r.png, r.info);
  pixels.resize(row_bytes * h);
  rows.resize(h);
  for (png_uint_32 j = 0; j < h; ++j) rows[j] = pixels.data() + row_bytes * j;
  png_read_image(r.png, rows.data());
  png_read_end(r.png, nullptr);

  map->width = int(w), map->height = int(h);
  map->texels.resize(size_t(w) * h);
  const double full = depth == 16 ? 65535.0 : 255.0;
  uint64_t fnv = 1469598103934665603ull;
  for (png_uint_32 j = 0; j < h; ++j)
    for (png_uint_32 i = 0; i < w; ++i) {
      double v[2];
      for (int c = 0; c < 2; ++c) {
        const png_byte* px = rows[j] + (size_t(i) * channels + c) * (depth == 16 ? 2 : 1);
        const unsigned value = depth == 16 ? (unsigned(px[0]) << 8) | px[1] : px[0];
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
