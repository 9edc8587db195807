// `cloudgen noise`: bake one tile of fractal noise to a float32 cube plus a JSON sidecar, or print
// the reference-mode Perlin value at one point.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "cloudgen/cli_parse.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "commands.h"
#include "noise3d/noise3d.h"

namespace cloudgen::cli {
namespace {

struct NoiseArgs {
  std::string kind = "perlin", period = "4", at, out;
  int octaves = 1, threads = 0;
  double gain = 0.5, lacunarity = 2;
  std::string seed = "0";
  uint32_t size = 64;
  bool dbl = false, reference = false;
};

void run_noise(const NoiseArgs& a) {
  if (a.reference) {
    if (a.at.empty()) throw InputError("--reference needs --at X,Y,Z");
    auto p = parse_number_list(a.at, "--at", 3, 3);
    std::printf("%.17g\n", noise3d::perlin_reference(p[0], p[1], p[2]));
    return;
  }
  if (a.out.empty()) throw InputError("-o/--output is required (or --reference --at X,Y,Z)");
  const std::string side = std::filesystem::path(a.out).replace_extension(".json").string();
  OutputBatch batch;  // the cube and its sidecar appear together or not at all
  batch.claim(a.out, "the noise cube");
  batch.claim(side, "the sidecar of " + a.out);
  noise3d::FractalParams p;
  p.kind = noise3d::parse_kind(a.kind);
  auto per = parse_number_list(a.period, "--period", 1, 3);
  for (double v : per)
    if (v != std::floor(v) || v < 1 || v > noise3d::kMaxPeriod)
      throw InputError("--period: " + a.period + " must be integers in [1, " + std::to_string(noise3d::kMaxPeriod) + "]");
  p.period = per.size() == 1 ? noise3d::Period::cube(uint32_t(per[0]))
                             : noise3d::Period{uint32_t(per[0]), uint32_t(per[1]), uint32_t(per[2])};
  p.octaves = a.octaves;
  p.gain = a.gain;
  p.lacunarity = a.lacunarity;
  p.seed = parse_uint(a.seed, "--seed", ~uint64_t(0));
  noise3d::validate(p);
  if (a.size < 1 || a.size > 2048) throw InputError("--size: " + std::to_string(a.size) + " must be in [1, 2048]");
  const noise3d::GridRegion r = noise3d::GridRegion::whole(a.size);
  std::vector<float> cube(r.count());
  const auto t0 = std::chrono::steady_clock::now();
  noise3d::MinMax mm;
  if (a.dbl) {
    std::vector<double> d(r.count());
    mm = noise3d::evaluate_grid(p, r, d.data(), {a.threads});
    for (size_t i = 0; i < d.size(); ++i) cube[i] = float(d[i]);
  } else {
    mm = noise3d::evaluate_grid(p, r, cube.data(), {a.threads});
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (g_cancel) throw Cancelled();
  nlohmann::json j;
  j["size"] = {a.size, a.size, a.size};
  j["kind"] = a.kind;
  j["dtype"] = "float32";
  j["memory_order"] = "x fastest, then y, then z; the cube spans exactly one period (one tile)";
  j["params"] = {{"period", {p.period.x, p.period.y, p.period.z}}, {"octaves", p.octaves}, {"gain", p.gain},
                 {"lacunarity", p.lacunarity}, {"seed", p.seed}, {"precision", a.dbl ? "double" : "float"}};
  auto range = noise3d::value_range(p.kind);
  j["range"] = {range[0], range[1]};
  j["min"] = mm.min;
  j["max"] = mm.max;
  j["generator"] = std::string("cloudgen ") + CLOUDGEN_VERSION;
  batch.stage(a.out, [&](const std::string& tmp) { write_file_bytes(tmp, cube.data(), cube.size() * sizeof(float)); });
  const std::string text = j.dump(2) + "\n";
  batch.stage(side, [&](const std::string& tmp) { write_file_bytes(tmp, text.data(), text.size()); });
  if (g_cancel) throw Cancelled();
  batch.commit();
  std::fprintf(stderr, "%s: %u^3 %s, min %.6f max %.6f, %.3f s (%.2f ns/sample)\n", a.out.c_str(), a.size,
               a.kind.c_str(), mm.min, mm.max, secs, secs * 1e9 / double(r.count()));
}

}  // namespace

void add_noise_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<NoiseArgs>();
  CLI::App* c = app.add_subcommand("noise", "Bake one tile of tileable noise to a float32 cube (+ JSON sidecar).");
  c->footer(
      "The cube is exactly one tile: --size N voxels span one --period, so copies laid side by side are\n"
      "seamless. Output: N^3 little-endian float32, x fastest, then y, then z; CUBE.json holds size,\n"
      "kind, params, min and max. Ranges: perlin in [-1, 1] (fBm normalised by 1.0363538 * sum of\n"
      "amplitudes), worley and perlin-worley in [0, 1].\n\n"
      "Examples:\n"
      "  cloudgen noise --kind worley --period 4 --octaves 5 --size 128 -o worley.raw\n"
      "  cloudgen noise --kind perlin --reference --at 3.14,42,7   # Perlin's ImprovedNoise: 0.13691995878400012");
  c->add_option("--kind", a->kind, "perlin | worley | perlin-worley")->check(CLI::IsMember({"perlin", "worley", "perlin-worley"}));
  c->add_option("--period", a->period,
                "Base period in lattice cells: P or PX,PY,PZ, each 1.." + std::to_string(noise3d::kMaxPeriod));
  // Ranges from libnoise3d's own limits (what noise3d::validate checks), not restated by hand.
  c->add_option("--octaves", a->octaves, "fBm octaves, 1.." + std::to_string(noise3d::kMaxOctaves))
      ->check(CLI::Range(1, noise3d::kMaxOctaves));
  c->add_option("--gain", a->gain, "Amplitude ratio between octaves, (0, 1]");
  c->add_option("--lacunarity", a->lacunarity,
                "Integer frequency ratio between octaves, 2.." + std::to_string(noise3d::kMaxLacunarity) +
                    " (non-integers break the wrap)");
  c->add_option("--seed", a->seed, "Seed: an integer in [0, 2^64 - 1]");
  c->add_option("--size", a->size, "Voxels per axis spanning one tile, 1..2048")->check(CLI::Range(1, 2048));
  c->add_option("-o,--output", a->out, "Output cube (.raw); the sidecar is written beside it as .json");
  c->add_option("--threads", a->threads, "Worker threads (0 = all cores); output is identical for any count")
      ->check(CLI::Range(0, kMaxThreads));
  c->add_flag("--double", a->dbl, "Evaluate in double precision (output stays float32)");
  c->add_flag("--reference", a->reference, "Print Perlin's reference ImprovedNoise (period 256, double) at --at");
  c->add_option("--at", a->at, "X,Y,Z for --reference");
  c->callback([a, &run] { run = [a] { run_noise(*a); }; });
}

}  // namespace cloudgen::cli
