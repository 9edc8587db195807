// libFuzzer target for the painted weather map reader (coverage.kind "image", weather_map.h): the
// input is the PNG's bytes. It is decoded or refused with InputError; what is decoded is read
// back as the pipeline reads it (bilinear columns, wrapped and clamped, and their height profiles),
// which must stay in [0, 1].
#include <cmath>
#include <cstdint>

#include "cloudgen/preset.h"
#include "cloudgen/weather_map.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return fuzz::guarded([&] {
    const auto map = cloudgen::read_weather_map_png(data, size, "fuzz.png");
    if ((map->channels != 1 && map->channels != 3) || map->width < 1 || map->height < 1 ||
        map->texels.size() != size_t(map->width) * size_t(map->height) * size_t(map->channels))
      __builtin_trap();
    cloudgen::Preset p;
    p.coverage_enabled = p.coverage_image = true;
    p.height_profile = cloudgen::HeightProfile::Cumulus;
    p.weather_map = map;
    for (bool tiling : {true, false}) {
      p.tiling = tiling;
      const cloudgen::WeatherColumns c = cloudgen::weather_columns(p, 7, 5, 1);
      for (size_t k = 0; k < c.coverage.size(); ++k) {
        for (float v : {c.coverage[k], c.type[k], c.top[k]})
          if (!(v >= 0 && v <= 1)) __builtin_trap();
        for (double h : {0.05, 0.5, 0.95}) {
          const float f = cloudgen::column_profile(p, c, k, h);
          if (!(f >= 0 && f <= 1)) __builtin_trap();
        }
      }
    }
  });
}
