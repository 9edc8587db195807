// Painted weather maps (coverage.kind = "image", docs/shaping.md): a PNG over the volume's x-z
// extent whose R is the coverage, G the cloud type (0 stratus, 0.5 cumulus, 1 cumulonimbus) and B
// the cloud-top height as a fraction of the volume's height; a grey image is coverage only. The
// reader (with its limits), the per-column lookup the pipeline multiplies in, and the writer of
// `cloudgen weather-map`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cloudgen/preset.h"

namespace cloudgen {

/// A weather map is a few hundred to a few thousand texels a side; 4096 bounds what a mistaken
/// file can make us allocate (4096^2 texels: 192 MiB of floats) before libpng reads a row.
constexpr int kWeatherMapMaxSide = 4096;

/// A decoded weather map: values in [0, 1] as stored (no gamma), row 0 = z = 0 side.
struct WeatherMap {
  std::string path;
  int width = 0, height = 0;
  int channels = 0;           ///< 1 (grey: coverage only) or 3 (R coverage, G type, B top)
  std::vector<float> texels;  ///< [row][column][channel]
  uint64_t fnv1a = 0;         ///< of the stored values, for preset_hash
};

/// Decodes a PNG held in memory (8- or 16-bit grey, grey + alpha, RGB or RGBA; alpha ignored).
/// InputError "coverage.file PATH: ..." naming what is allowed for anything else.
std::shared_ptr<const WeatherMap> read_weather_map_png(const uint8_t* data, size_t size, const std::string& path);
/// Reads and decodes a file (missing, not regular, too big: InputError naming the file).
std::shared_ptr<const WeatherMap> load_weather_map(const std::string& path);

/// Coverage, cloud type and top height on a w x h grid of columns over the x-z extent (cell centres
/// at ((i + 0.5) / w, (j + 0.5) / h)), [j * w + i]. From the image (bilinear, wrapping when the
/// preset tiles, clamped otherwise) or from the preset's noise coverage (1 when disabled, its
/// cloud type and top 1). `typed`: the type varies per column (an RGB image and a cloud-type
/// profile); otherwise the preset's own height profile applies.
struct WeatherColumns {
  uint32_t w = 0, h = 0;
  std::vector<float> coverage, type, top;
  bool typed = false;
};
WeatherColumns weather_columns(const Preset& p, uint32_t w, uint32_t h, int threads = 0);

/// The preset's cloud type as a G value: stratus 0, cumulus 0.5, cumulonimbus 1 (0.5 for the
/// exponential profile, which ignores G).
float preset_cloud_type(const Preset& p);

/// The height profile of one column at normalised height hn: 0 at or above the top, else the
/// type's gradient (or the preset's profile) at hn / top, clamped to [0, 1].
float column_profile(const Preset& p, const WeatherColumns& c, size_t column, double hn);

/// Writes the columns as a 16-bit RGB PNG (R coverage, G type, B top), which load_weather_map reads.
void write_weather_map_png(const std::string& file, const WeatherColumns& c);

}  // namespace cloudgen
