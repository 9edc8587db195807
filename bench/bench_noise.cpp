// libnoise3d throughput over a 128^3 tile, single-threaded and on all cores, against plain scalar
// implementations written here (per-sample hashing of all corners / all 27 cells, the way most
// tileable cloud-noise generators do it), measured in the same run so the ratio is meaningful.
//
//   build/bin/bench_noise --benchmark_counters_tabular=true
//
// Counter ns_per_eval = wall time / (samples * octaves): the cost of one single-octave evaluation.
#include <benchmark/benchmark.h>

#include <cmath>
#include <thread>
#include <vector>

#include "detail.h"
#include "fractal_detail.h"
#include "noise3d/noise3d.h"

using namespace noise3d;

namespace {

constexpr uint32_t kN = 128;

// ---- plain scalar references --------------------------------------------------------------
float ref_perlin(double x, double y, double z, uint32_t P, uint32_t key) {
  using namespace detail;
  double fx0 = std::floor(x), fy0 = std::floor(y), fz0 = std::floor(z);
  int64_t ix = int64_t(fx0), iy = int64_t(fy0), iz = int64_t(fz0);
  float fx = float(x - fx0), fy = float(y - fy0), fz = float(z - fz0);
  float u = fade(fx), v = fade(fy), w = fade(fz);
  float r = 0;
  for (int c = 0; c < 8; ++c) {
    int bx = c & 1, by = (c >> 1) & 1, bz = c >> 2;
    uint32_t g = grad_index(hash3(wrap(ix + bx, P), wrap(iy + by, P), wrap(iz + bz, P), key));
    float d = kGradX[g] * (fx - bx) + kGradY[g] * (fy - by) + kGradZ[g] * (fz - bz);
    r += (bx ? u : 1 - u) * (by ? v : 1 - v) * (bz ? w : 1 - w) * d;
  }
  return r;
}

float ref_worley(double x, double y, double z, uint32_t P, uint32_t key) {
  using namespace detail;
  double fx0 = std::floor(x), fy0 = std::floor(y), fz0 = std::floor(z);
  int64_t ix = int64_t(fx0), iy = int64_t(fy0), iz = int64_t(fz0);
  float fx = float(x - fx0), fy = float(y - fy0), fz = float(z - fz0);
  float best = 1e30f;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        uint32_t h = hash3(wrap(ix + dx, P), wrap(iy + dy, P), wrap(iz + dz, P), key);
        float ex = dx + jitter01<float>(jitter_hash(h, 0)) - fx;
        float ey = dy + jitter01<float>(jitter_hash(h, 1)) - fy;
        float ez = dz + jitter01<float>(jitter_hash(h, 2)) - fz;
        best = std::min(best, ex * ex + ey * ey + ez * ez);
      }
  return 1.0f - std::sqrt(best) / float(kSqrt3);
}

FractalParams params(Kind k, int octaves) {
  FractalParams p;
  p.kind = k;
  p.period = Period::cube(8);
  p.octaves = octaves;
  p.seed = 1;
  return p;
}

void report(benchmark::State& st, int octaves) {
  const double evals = double(kN) * kN * kN * octaves;
  st.counters["ns_per_eval"] = benchmark::Counter(evals * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                                   benchmark::Counter::kInvert);
  st.counters["Msamples_per_s"] = benchmark::Counter(double(kN) * kN * kN * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Library(benchmark::State& st) {
  const Kind k = Kind(st.range(0));
  const int octaves = int(st.range(1)), threads = int(st.range(2));
  std::vector<float> out(size_t(kN) * kN * kN);
  for (auto _ : st) {
    evaluate_grid(params(k, octaves), GridRegion::whole(kN), out.data(), {threads});
    benchmark::DoNotOptimize(out.data());
  }
  st.SetLabel(std::string(kind_name(k)) + (threads == 1 ? " 1 thread" : " all cores"));
  report(st, octaves);
}

void BM_ScalarReference(benchmark::State& st) {
  const Kind k = Kind(st.range(0));
  const int octaves = int(st.range(1));
  const FractalParams p = params(k, octaves);
  const auto ocs = detail::octaves(p, k);
  std::vector<float> out(size_t(kN) * kN * kN);
  for (auto _ : st) {
    size_t q = 0;
    for (uint32_t z = 0; z < kN; ++z)
      for (uint32_t y = 0; y < kN; ++y)
        for (uint32_t x = 0; x < kN; ++x, ++q) {
          float s = 0;
          for (const auto& oc : ocs) {
            const uint32_t P = oc.period.x;
            const uint32_t key = detail::seed_key(oc.seed, k == Kind::Worley ? 0x3a71u : 0x9e11u);
            const double px = double(x) * P / kN, py = double(y) * P / kN, pz = double(z) * P / kN;
            s += float(oc.weight) * (k == Kind::Perlin ? ref_perlin(px, py, pz, P, key) : ref_worley(px, py, pz, P, key));
          }
          out[q] = s;
        }
    benchmark::DoNotOptimize(out.data());
  }
  st.SetLabel(std::string("scalar reference ") + kind_name(k) + " 1 thread");
  report(st, octaves);
}

const int kAll = int(std::thread::hardware_concurrency());

}  // namespace

BENCHMARK(BM_ScalarReference)->Args({int(Kind::Perlin), 1})->Args({int(Kind::Worley), 1})
    ->Args({int(Kind::Perlin), 5})->Args({int(Kind::Worley), 5})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Library)
    ->Args({int(Kind::Perlin), 1, 1})->Args({int(Kind::Perlin), 1, kAll})
    ->Args({int(Kind::Worley), 1, 1})->Args({int(Kind::Worley), 1, kAll})
    ->Args({int(Kind::Perlin), 5, 1})->Args({int(Kind::Perlin), 5, kAll})
    ->Args({int(Kind::Worley), 5, 1})->Args({int(Kind::Worley), 5, kAll})
    ->Args({int(Kind::PerlinWorley), 5, 1})->Args({int(Kind::PerlinWorley), 5, kAll})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
