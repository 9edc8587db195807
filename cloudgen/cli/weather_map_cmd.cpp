// `cloudgen weather-map`: the coverage, cloud type and cloud-top height a preset produces, written
// as the 16-bit RGB PNG that coverage.kind "image" reads back (docs/shaping.md), to paint over.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cloudgen/output.h"
#include "cloudgen/preset.h"
#include "cloudgen/printable.h"
#include "cloudgen/weather_map.h"
#include "commands.h"

namespace cloudgen::cli {
namespace {

struct WeatherMapArgs {
  std::string preset, out;
  std::vector<std::string> sets;
  uint32_t size = 0;
  bool quiet = false;
};

void run_weather_map(const WeatherMapArgs& a) {
  const std::string path = resolve_preset_path(a.preset);
  const Preset p = load_preset(path, a.sets);
  if (!p.shape.sources.empty())
    throw InputError(path + ": /shape/sources: shape sources replace the coverage; a weather map needs a preset without them");
  const std::string ext = a.out.size() >= 4 ? a.out.substr(a.out.size() - 4) : "";
  if (ext != ".png" && ext != ".PNG") throw InputError("-o " + printable(a.out) + ": a weather map is written as .png");
  const uint32_t most = kWeatherMapMaxSide;
  if (a.size > most) throw InputError("--size " + std::to_string(a.size) + ": at most " + std::to_string(most));
  // Default: one texel per voxel column; --size N: the longer side N, the other in proportion.
  uint32_t w = std::min(p.resolution[0], most), h = std::min(p.resolution[2], most);
  if (a.size) {
    const double f = double(a.size) / std::max(p.resolution[0], p.resolution[2]);
    w = std::max<uint32_t>(1, uint32_t(std::lround(p.resolution[0] * f)));
    h = std::max<uint32_t>(1, uint32_t(std::lround(p.resolution[2] * f)));
  }
  OutputBatch batch;
  batch.protect(path, "the input preset " + path);
  if (p.weather_map) batch.protect(p.weather_map->path, "the preset's weather map " + p.weather_map->path);
  batch.claim(a.out, "the weather map");
  const WeatherColumns c = weather_columns(p, w, h);
  batch.stage(a.out, [&](const std::string& tmp) { write_weather_map_png(tmp, c); });
  if (g_cancel) throw Cancelled();
  batch.commit();
  if (!a.quiet)
    std::fprintf(stderr,
                 "wrote %s: %ux%u 16-bit weather map (x right, z down; R = coverage, G = cloud type, B = top); use it "
                 "with --set coverage.kind=image --set coverage.file=%s\n",
                 printable(a.out).c_str(), w, h, printable(a.out).c_str());
}

}  // namespace

void add_weather_map_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<WeatherMapArgs>();
  CLI::App* c = app.add_subcommand("weather-map", "Write a preset's coverage, cloud type and top as a PNG to paint over.");
  c->footer(
      "The PNG covers the volume's x-z extent (x to the right, z down, texel centres at voxel\n"
      "columns): R = coverage in [0, 1], G = cloud type (0 stratus, 0.5 cumulus, 1 cumulonimbus),\n"
      "B = cloud-top height as a fraction of the volume's height; 16-bit RGB. Fed back with\n"
      "coverage.kind=image and coverage.file=FILE it gives the same clouds (docs/shaping.md).\n\n"
      "Examples:\n"
      "  cloudgen weather-map cumulus-field -o out/weather.png\n"
      "  cloudgen generate cumulus-field --set coverage.kind=image \\\n"
      "      --set coverage.file=out/weather.png -o out/painted.vdb");
  c->add_option("preset", a->preset, "Preset file or shipped preset name")->required();
  c->add_option("-o,--output", a->out, "Output image (.png)")->required();
  c->add_option("--size", a->size, "Longer side in texels (default: one texel per voxel column)");
  c->add_option("--set", a->sets, "Overrides, as for generate");
  c->add_flag("-q,--quiet", a->quiet, "No summary line");
  c->callback([a, &run] { run = [a] { run_weather_map(*a); }; });
}

}  // namespace cloudgen::cli
