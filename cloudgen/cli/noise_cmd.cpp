// `cloudgen noise`: bake one tile of fractal noise to a float32 cube plus a JSON sidecar, or print
// the reference-mode Perlin value at one point.
#include <array>
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
#include "cloudgen/printable.h"
#include "cloudgen/schema.h"
#include "commands.h"
#include "noise3d/noise3d.h"

namespace cloudgen::cli {
namespace {

FieldSpec flag(std::string name, std::string type, std::string def, std::string doc, double lo, double hi,
               std::vector<std::string> choices = {}, std::string allowed = {}) {
  FieldSpec f;
  f.name = std::move(name), f.type = std::move(type), f.default_value = std::move(def), f.doc = std::move(doc);
  f.lo = lo, f.hi = hi, f.choices = std::move(choices), f.allowed = std::move(allowed);
  return f;
}

// The noise flags in one table (cloudgen/schema.h; defaults as the flag's text), with libnoise3d's own limits (what
// noise3d::validate checks): the help text and every check come from here, as a preset's keys do.
enum NoiseFlag { kKind, kPeriod, kOctaves, kGain, kLacunarity, kSeed, kSize, kNoiseFlags };
const std::vector<FieldSpec>& noise_flags() {
  static const std::vector<FieldSpec> f = {
      flag("--kind", "string", "perlin", "Noise kind", 0, 0, {"perlin", "worley", "perlin-worley"}),
      flag("--period", "period", "4", "Base period in lattice cells: P or PX,PY,PZ", 1, noise3d::kMaxPeriod),
      flag("--octaves", "integer", "1", "fBm octaves", 1, noise3d::kMaxOctaves),
      flag("--gain", "number", "0.5", "Amplitude ratio between octaves", 1e-6, 1),
      flag("--lacunarity", "integer", "2", "Frequency ratio between octaves (an integer: non-integers break the wrap)", 2,
           noise3d::kMaxLacunarity),
      // 2^64 - 1 is beyond a double: parse_uint checks the seed exactly, the table gives its words.
      flag("--seed", "integer", "0", "Seed", 0, 0, {}, "integer in [0, 2^64 - 1]"),
      flag("--size", "integer", "64", "Voxels per axis spanning one tile", 1, 2048),
  };
  return f;
}

struct NoiseArgs {
  std::array<std::string, kNoiseFlags> value;  ///< as given (or the table's default), by NoiseFlag
  std::string at, out;
  int threads = 0;
  bool dbl = false, reference = false;
};

/// Each flag's value checked against its table entry: every problem at once, as
/// "--octaves: 40 is out of range; allowed: integer in [1, 16]".
std::array<nlohmann::json, kNoiseFlags> checked_flags(const NoiseArgs& a) {
  std::array<nlohmann::json, kNoiseFlags> v;
  std::string problems;
  auto problem = [&](const std::string& ptr, const std::string& what) { problems += (problems.empty() ? "" : "\n") + ptr + ": " + what; };
  for (int i = 0; i < kNoiseFlags; ++i) {
    const FieldSpec& f = noise_flags()[size_t(i)];
    const std::string& text = a.value[size_t(i)];
    if (i == kSeed) {
      v[size_t(i)] = parse_uint(text, f.name, ~uint64_t(0));
      continue;
    }
    if (i == kPeriod) {  // P or PX,PY,PZ (non-finite and malformed lists are refused here)
      nlohmann::json list = nlohmann::json::array();
      for (double d : parse_number_list(text, f.name, 1, 3))  // whole numbers shown as the user wrote them
        list.push_back(d == std::floor(d) && std::fabs(d) < 9007199254740992.0 ? nlohmann::json(int64_t(d)) : nlohmann::json(d));
      v[size_t(i)] = list.size() == 1 ? list[0] : list;
    } else if (f.type == "string") {
      v[size_t(i)] = text;
    } else {
      v[size_t(i)] = nlohmann::json::parse(text, nullptr, false);
      if (v[size_t(i)].is_discarded()) v[size_t(i)] = text;  // not a number: the checker says so
    }
    check_value(f, v[size_t(i)], f.name, problem);
  }
  if (!problems.empty()) throw InputError(problems);
  return v;
}

void run_noise(const NoiseArgs& a) {
  if (a.reference) {
    if (a.at.empty()) throw InputError("--reference needs --at X,Y,Z");
    auto p = parse_number_list(a.at, "--at", 3, 3);
    std::printf("%.17g\n", noise3d::perlin_reference(p[0], p[1], p[2]));
    return;
  }
  if (a.out.empty()) throw InputError("-o/--output is required (or --reference --at X,Y,Z)");
  const auto v = checked_flags(a);
  const std::string side = std::filesystem::path(a.out).replace_extension(".json").string();
  OutputBatch batch;  // the cube and its sidecar appear together or not at all
  batch.claim(a.out, "the noise cube");
  batch.claim(side, "the sidecar of " + a.out);
  noise3d::FractalParams p;
  const std::string kind = v[kKind].get<std::string>();
  p.kind = noise3d::parse_kind(kind);
  const nlohmann::json& per = v[kPeriod];
  p.period = per.is_array() ? noise3d::Period{per[0].get<uint32_t>(), per[1].get<uint32_t>(), per[2].get<uint32_t>()}
                            : noise3d::Period::cube(per.get<uint32_t>());
  p.octaves = v[kOctaves].get<int>();
  p.gain = v[kGain].get<double>();
  p.lacunarity = v[kLacunarity].get<double>();
  p.seed = v[kSeed].get<uint64_t>();
  noise3d::validate(p);
  const uint32_t size = v[kSize].get<uint32_t>();
  const noise3d::GridRegion r = noise3d::GridRegion::whole(size);
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
  j["size"] = {size, size, size};
  j["kind"] = kind;
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
  std::fprintf(stderr, "%s: %u^3 %s, min %.6f max %.6f, %.3f s (%.2f ns/sample)\n", printable(a.out).c_str(), size,
               kind.c_str(), mm.min, mm.max, secs, secs * 1e9 / double(r.count()));
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
      "  cloudgen noise --kind perlin --reference --at 3.14,42,7   # Perlin's ImprovedNoise: 0.136919958784");
  for (int i = 0; i < kNoiseFlags; ++i) {
    const FieldSpec& f = noise_flags()[size_t(i)];
    a->value[size_t(i)] = f.default_value;
    c->add_option(f.name, a->value[size_t(i)], f.doc + ": " + f.range() + " (default " + f.default_value + ")");
  }
  c->add_option("-o,--output", a->out, "Output cube (.raw); the sidecar is written beside it as .json");
  c->add_option("--threads", a->threads, "Worker threads (0 = all cores); output is identical for any count")
      ->check(CLI::Range(0, kMaxThreads));
  c->add_flag("--double", a->dbl, "Evaluate in double precision (output stays float32)");
  c->add_flag("--reference", a->reference, "Print Perlin's reference ImprovedNoise (period 256, double) at --at");
  c->add_option("--at", a->at, "X,Y,Z for --reference");
  c->callback([a, &run] { run = [a] { run_noise(*a); }; });
}

}  // namespace cloudgen::cli
