// Painted weather maps: the PNG reader (cloudgen/png_read.h, shared with the flow maps), the
// bilinear per-column lookup and the 16-bit writer.
#include "cloudgen/weather_map.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "cloudgen/generate.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/output.h"
#include "cloudgen/png_read.h"

namespace cloudgen {
namespace {

const char* const kAllowed = "a weather map is an 8- or 16-bit grey, RGB or RGBA PNG (R = coverage, G = cloud type, "
                             "B = cloud-top height; grey = coverage only)";

/// Checks the header: size within the limit, 8 or 16 bits, not a palette.
void check_header(const std::string& what, const PngHeader& h) {
  if (h.width == 0 || h.height == 0) throw InputError(what + ": the image is empty (0 texels); " + kAllowed);
  if (h.width > uint32_t(kWeatherMapMaxSide) || h.height > uint32_t(kWeatherMapMaxSide))
    throw InputError(what + ": " + std::to_string(h.width) + " x " + std::to_string(h.height) +
                     " texels; a weather map may have at most " + std::to_string(kWeatherMapMaxSide) + " a side");
  if (h.palette) throw InputError(what + ": a palette image; " + kAllowed);
  if (h.depth != 8 && h.depth != 16)
    throw InputError(what + ": " + std::to_string(h.depth) + "-bit samples; " + kAllowed);
}

/// The decoded texels into map (values / full scale, FNV-1a of the stored values).
void take_pixels(WeatherMap& map, const PngPixels& px) {
  const size_t w = size_t(map.width), h = size_t(map.height);
  const int nc = map.channels;
  map.texels.resize(w * h * size_t(nc));
  const double full = px.depth == 16 ? 65535.0 : 255.0;
  uint64_t fnv = 1469598103934665603ull;
  for (size_t j = 0; j < h; ++j)
    for (size_t i = 0; i < w; ++i)
      for (int c = 0; c < nc; ++c) {
        const unsigned value = px.value(i, j, c);
        for (int b = 0; b < 2; ++b) fnv = (fnv ^ ((value >> (8 * b)) & 0xff)) * 1099511628211ull;
        map.texels[(j * w + i) * size_t(nc) + size_t(c)] = float(double(value) / full);
      }
  map.fnv1a = fnv;
}

/// Bilinear lookup of channel c at the point (u, v) in [0, 1]^2 of the x-z extent; texel centres
/// at ((i + 0.5) / width, (j + 0.5) / height); wrapping or clamped at the edges.
float sample(const WeatherMap& m, int c, double u, double v, bool wrap) {
  auto axis = [wrap](double t, int n, int& i0, int& i1, double& f) {
    double x = t * n - 0.5;
    if (!wrap) x = std::clamp(x, 0.0, double(n - 1));
    const double fl = std::floor(x);
    f = x - fl;
    if (wrap) {
      i0 = int((int64_t(fl) % n + n) % n), i1 = (i0 + 1) % n;
    } else {
      i0 = int(fl), i1 = std::min(i0 + 1, n - 1);
    }
  };
  int x0, x1, y0, y1;
  double fx, fy;
  axis(u, m.width, x0, x1, fx);
  axis(v, m.height, y0, y1, fy);
  auto at = [&](int i, int j) { return double(m.texels[(size_t(j) * size_t(m.width) + size_t(i)) * size_t(m.channels) + size_t(c)]); };
  const double top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
  const double bot = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
  return float(std::clamp(top + (bot - top) * fy, 0.0, 1.0));
}

}  // namespace

std::shared_ptr<const WeatherMap> read_weather_map_png(const uint8_t* data, size_t size, const std::string& path) {
  const std::string what = "coverage.file " + path;
  if (!is_png(data, size)) throw InputError(what + ": not a PNG file; " + kAllowed);
  const PngPixels px =
      decode_png(data, size, what, [&](const PngHeader& h) { check_header(what, h); }, std::string("; ") + kAllowed);
  auto map = std::make_shared<WeatherMap>();
  map->path = path;
  map->width = int(px.width), map->height = int(px.height);
  map->channels = px.channels >= 3 ? 3 : 1;
  take_pixels(*map, px);
  return map;
}

std::shared_ptr<const WeatherMap> load_weather_map(const std::string& path) {
  const std::string what = "coverage.file " + path;
  // The one input layer (cloudgen/input_scope.h) says what the file may be and how much is read.
  // 4096^2 RGBA at 16 bits, uncompressed, is 128 MiB; a PNG bigger than that is not a weather map.
  const std::vector<uint8_t> bytes = read_input_bytes(path, "the weather map " + path, what, size_t(1) << 28);
  if (bytes.empty()) throw InputError(what + ": the file is empty (0 bytes); " + kAllowed);
  return read_weather_map_png(bytes.data(), bytes.size(), path);
}

float preset_cloud_type(const Preset& p) {
  switch (p.height_profile) {
    case HeightProfile::Stratus: return 0.0f;
    case HeightProfile::Cumulonimbus: return 1.0f;
    default: return 0.5f;
  }
}

WeatherColumns weather_columns(const Preset& p, uint32_t w, uint32_t h, int threads) {
  WeatherColumns c;
  c.w = w, c.h = h;
  const size_t n = size_t(w) * h;
  if (p.coverage_enabled && p.coverage_image && p.weather_map) {
    const WeatherMap& m = *p.weather_map;
    c.coverage.resize(n), c.type.assign(n, preset_cloud_type(p)), c.top.assign(n, 1.0f);
    c.typed = m.channels == 3 && p.height_profile != HeightProfile::Exponential;
    for (uint32_t j = 0; j < h; ++j)
      for (uint32_t i = 0; i < w; ++i) {
        const double u = (i + 0.5) / w, v = (j + 0.5) / h;
        const size_t k = size_t(j) * w + i;
        c.coverage[k] = sample(m, 0, u, v, p.tiling);
        if (m.channels == 3) {
          if (c.typed) c.type[k] = sample(m, 1, u, v, p.tiling);
          c.top[k] = sample(m, 2, u, v, p.tiling);
        }
      }
    return c;
  }
  c.coverage = p.coverage_enabled ? coverage_grid(p, w, h, threads) : std::vector<float>(n, 1.0f);
  c.type.assign(n, preset_cloud_type(p)), c.top.assign(n, 1.0f);
  return c;
}

float column_profile(const Preset& p, const WeatherColumns& c, size_t column, double hn) {
  const double hs = hn / double(c.top[column]);
  if (!(hs < 1.0)) return 0.0f;  // at or above the top (a top of 0: no cloud)
  const double v = c.typed ? cloud_type_height_gradient(hs, double(c.type[column])) : height_profile(p, hs);
  return float(std::clamp(v, 0.0, 1.0));
}

void write_weather_map_png(const std::string& file, const WeatherColumns& c) {
  std::vector<uint16_t> img(size_t(c.w) * c.h * 3);
  auto q = [](float v) { return uint16_t(std::lround(std::clamp(double(v), 0.0, 1.0) * 65535.0)); };
  for (size_t k = 0; k < size_t(c.w) * c.h; ++k)
    img[3 * k] = q(c.coverage[k]), img[3 * k + 1] = q(c.type[k]), img[3 * k + 2] = q(c.top[k]);
  png_image im;
  std::memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  im.width = c.w, im.height = c.h, im.format = PNG_FORMAT_LINEAR_RGB;
  if (!png_image_write_to_file(&im, file.c_str(), 0, img.data(), 0, nullptr))
    throw IoError(file + ": PNG write failed: " + im.message);
  png_image_free(&im);
}

}  // namespace cloudgen
