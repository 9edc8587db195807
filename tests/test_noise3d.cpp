// libnoise3d: invariants (tiling, continuity, ranges, exactness, determinism, divergence) and a few
// pinned values. Every check here can fail if the noise changes or breaks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "detail.h"
#include "fractal_detail.h"
#include "noise3d/noise3d.h"

using namespace noise3d;

namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 g(12345);
  return g;
}
double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng()); }

// Ken Perlin's ImprovedNoise, transcribed independently here from the 2002 paper's Java listing
// (the library's copy lives in reference.cpp); the tests compare the two and pin published values.
struct JavaImprovedNoise {
  int p[512];
  JavaImprovedNoise() {
    static const int permutation[] = {
        151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,
        103, 30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,
        0,   26,  197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149,
        56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166,
        77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,
        245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187,
        208, 89,  18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186,
        3,   64,  52,  217, 226, 250, 124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212,
        207, 206, 59,  227, 47,  16,  58,  17,  182, 189, 28,  42,  223, 183, 170, 213, 119, 248,
        152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,   129, 22,  39,  253,
        19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
        242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107,
        49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,
        150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243, 141, 128, 195, 78,  66,
        215, 61,  156, 180};
    for (int i = 0; i < 256; i++) p[256 + i] = p[i] = permutation[i];
  }
  static double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
  static double lerp(double t, double a, double b) { return a + t * (b - a); }
  static double grad(int hash, double x, double y, double z) {
    int h = hash & 15;
    double u = h < 8 ? x : y, v = h < 4 ? y : h == 12 || h == 14 ? x : z;
    return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
  }
  double noise(double x, double y, double z) const {
    int X = (int)std::floor(x) & 255, Y = (int)std::floor(y) & 255, Z = (int)std::floor(z) & 255;
    x -= std::floor(x), y -= std::floor(y), z -= std::floor(z);
    double u = fade(x), v = fade(y), w = fade(z);
    int A = p[X] + Y, AA = p[A] + Z, AB = p[A + 1] + Z, B = p[X + 1] + Y, BA = p[B] + Z, BB = p[B + 1] + Z;
    return lerp(w, lerp(v, lerp(u, grad(p[AA], x, y, z), grad(p[BA], x - 1, y, z)),
                        lerp(u, grad(p[AB], x, y - 1, z), grad(p[BB], x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(p[AA + 1], x, y, z - 1), grad(p[BA + 1], x - 1, y, z - 1)),
                     lerp(u, grad(p[AB + 1], x, y - 1, z - 1), grad(p[BB + 1], x - 1, y - 1, z - 1))));
  }
};

FractalParams fp(Kind k, uint32_t period, int octaves, uint64_t seed = 1) {
  FractalParams p;
  p.kind = k;
  p.period = Period::cube(period);
  p.octaves = octaves;
  p.seed = seed;
  return p;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(PerlinReference, MatchesPerlinsJavaCodeTo1e12) {
  JavaImprovedNoise java;
  for (int n = 0; n < 20000; ++n) {
    double x = uni(-600, 600), y = uni(-600, 600), z = uni(-600, 600);
    ASSERT_NEAR(perlin_reference(x, y, z), java.noise(x, y, z), 1e-12) << x << "," << y << "," << z;
  }
  // Value widely quoted for Perlin's own Java class: ImprovedNoise.noise(3.14, 42, 7).
  EXPECT_NEAR(perlin_reference(3.14, 42, 7), 0.13691995878400012, 1e-12);
  EXPECT_EQ(perlin_reference(1, 2, 3), 0.0);  // zero on the lattice
  EXPECT_NEAR(perlin_reference(0.5 + 256, 0.25, 0.75), perlin_reference(0.5, 0.25, 0.75), 1e-12);
}

// ---------------------------------------------------------------------------------------------
TEST(Tiling, PointFunctionsWrapOnEveryAxis) {
  for (uint32_t P : {1u, 3u, 7u, 256u, 1000u}) {
    Period per{P, P + (P > 1 ? 1u : 0u), P};  // also non-cubic periods
    const uint32_t pv[3] = {per.x, per.y, per.z};
    for (int n = 0; n < 300; ++n) {
      double q[3] = {uni(0, pv[0]), uni(0, pv[1]), uni(0, pv[2])};
      for (int a = 0; a < 3; ++a)
        for (int k : {-3, 1, 5}) {
          double s[3] = {q[0], q[1], q[2]};
          s[a] += double(k) * pv[a];
          EXPECT_EQ(perlin(q[0], q[1], q[2], per, 9), perlin(s[0], s[1], s[2], per, 9)) << P;
          EXPECT_NEAR(worley(q[0], q[1], q[2], per, 9).f1, worley(s[0], s[1], s[2], per, 9).f1, 1e-9) << P;
        }
    }
  }
}

TEST(Tiling, FbmWithEightOctavesWraps) {
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley})
    for (uint32_t P : {1u, 3u, 7u}) {
      FractalParams p = fp(k, P, 8);
      for (int n = 0; n < 100; ++n) {
        double x = uni(0, P), y = uni(0, P), z = uni(0, P);
        double v = evaluate(p, x, y, z);
        EXPECT_NEAR(v, evaluate(p, x + P, y, z), 1e-6);
        EXPECT_NEAR(v, evaluate(p, x, y - 2.0 * P, z), 1e-6);
        EXPECT_NEAR(v, evaluate(p, x, y, z + 3.0 * P), 1e-6);
      }
    }
}

TEST(Tiling, BatchCubeIsOneSeamlessTile) {
  // The cube's sample N would be sample 0 of the next tile: compare the point function there.
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley})
    for (uint32_t P : {3u, 7u}) {
      FractalParams p = fp(k, P, 3, 77);
      const uint32_t N = 20;
      std::vector<float> cube(N * N * N);
      evaluate_grid(p, GridRegion::whole(N), cube.data());
      for (uint32_t j = 0; j < N; j += 3)
        for (uint32_t i = 0; i < N; i += 3) {
          double x = double(i) * P / N, y = double(j) * P / N;
          // face x=0 vs x=P, y=0 vs y=P, z=0 vs z=P
          EXPECT_NEAR(cube[(0 * N + j) * N + i], evaluate(p, x, y, P), 1e-6);
          EXPECT_NEAR(cube[(j * N + 0) * N + i], evaluate(p, x, P, y), 1e-6);
          EXPECT_NEAR(cube[(j * N + i) * N + 0], evaluate(p, P, x, y), 1e-6);
        }
    }
}

TEST(Tiling, LargeCoordinatesAndPeriodsKeepTheWrap) {
  const Period big{1000000, 999983, 65536};
  for (int n = 0; n < 200; ++n) {
    double x = uni(0, 1000), y = uni(0, 1000), z = uni(0, 1000);
    double k = 1000.0;  // coordinates around 1e9: lattice index far beyond 2^16 and 2^24
    EXPECT_NEAR(perlin_d(x, y, z, big, 3), perlin_d(x + k * big.x, y + k * big.y, z + k * big.z, big, 3), 1e-6);
    EXPECT_NEAR(worley(x, y, z, big, 3).f1, worley(x - k * big.x, y, z + k * big.z, big, 3).f1, 1e-6);
  }
  // Negative coordinates wrap like positive ones.
  EXPECT_NEAR(perlin_d(-0.25, -7.5, -3.125, Period::cube(7), 5), perlin_d(6.75, 6.5, 3.875, Period::cube(7), 5), 1e-12);
}

// ---------------------------------------------------------------------------------------------
TEST(Continuity, FiniteDifferencesAreBoundedAcrossCellsAndSeams) {
  // |dN/dx| is bounded by the analytic derivative; a jump at a cell or tile seam would blow the
  // finite difference up by 1/h.
  const double h = 1e-5;
  double maxd = 0;
  for (int n = 0; n < 20000; ++n) {
    // Points straddling lattice planes and the tile seam (x = 0 == 5).
    double x = (n % 2) ? std::round(uni(0, 5)) - h / 2 : uni(0, 5);
    double y = uni(0, 5), z = uni(0, 5);
    double d = std::fabs(perlin_d(x + h, y, z, Period::cube(5), 2) - perlin_d(x, y, z, Period::cube(5), 2)) / h;
    maxd = std::max(maxd, d);
    ValueGrad g = perlin_grad(x, y, z, Period::cube(5), 2);
    ASSERT_LT(d, std::fabs(g.grad[0]) + 1e-3 + 10 * h * 30);
  }
  EXPECT_LT(maxd, 4.0);
}

TEST(Continuity, PerlinIsC2AtCellBoundaries) {
  // Second differences evaluated just left and just right of a lattice plane must agree
  // (a cubic fade would leave a jump in the second derivative).
  // One-sided second differences sit h from the plane, so they differ by ~2h*f''' (|f'''| < 200
  // here); a cubic fade's second-derivative jump is O(1).
  const double h = 1e-4;
  for (int n = 0; n < 2000; ++n) {
    double c = std::floor(uni(0, 7)), y = uni(0, 7), z = uni(0, 7);
    auto f = [&](double x) { return perlin_d(x, y, z, Period::cube(7), 4); };
    double left = (f(c - 2 * h) - 2 * f(c - h) + f(c)) / (h * h);
    double right = (f(c) - 2 * f(c + h) + f(c + 2 * h)) / (h * h);
    ASSERT_NEAR(left, right, 0.05) << "c=" << c;
  }
}

TEST(Continuity, AnalyticGradientMatchesFiniteDifferences) {
  const double h = 1e-6;
  for (int n = 0; n < 2000; ++n) {
    double x = uni(0, 9), y = uni(0, 9), z = uni(0, 9);
    ValueGrad g = perlin_grad(x, y, z, Period::cube(9), 4);
    EXPECT_NEAR(g.value, perlin_d(x, y, z, Period::cube(9), 4), 1e-12);
    EXPECT_NEAR(g.grad[0], (perlin_d(x + h, y, z, Period::cube(9), 4) - perlin_d(x - h, y, z, Period::cube(9), 4)) / (2 * h), 1e-6);
    EXPECT_NEAR(g.grad[1], (perlin_d(x, y + h, z, Period::cube(9), 4) - perlin_d(x, y - h, z, Period::cube(9), 4)) / (2 * h), 1e-6);
    EXPECT_NEAR(g.grad[2], (perlin_d(x, y, z + h, Period::cube(9), 4) - perlin_d(x, y, z - h, Period::cube(9), 4)) / (2 * h), 1e-6);
  }
}

// ---------------------------------------------------------------------------------------------
TEST(Statistics, PerlinRangeAndMeanOverAMillionPoints) {
  double sum = 0, mx = 0;
  const int n = 1000000;
  for (int i = 0; i < n; ++i) {
    float v = perlin(uni(0, 64), uni(0, 64), uni(0, 64), Period::cube(64), 11);
    ASSERT_LE(std::fabs(v), kPerlinBound + 1e-6);
    sum += v;
    mx = std::max(mx, double(std::fabs(v)));
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_GT(mx, 0.7);  // the range is actually used
}

TEST(Statistics, InvertedWorleyInUnitRange) {
  double lo = 1, hi = 0;
  for (int i = 0; i < 1000000; ++i) {
    float v = worley_inverted(uni(0, 16), uni(0, 16), uni(0, 16), Period::cube(16), 3);
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f);
    lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
  }
  EXPECT_GT(hi, 0.95);
  EXPECT_LT(lo, 0.6);
}

TEST(Statistics, FbmWithinNormalisedRange) {
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley}) {
    FractalParams p = fp(k, 4, 5, 21);
    p.gain = 0.9;
    auto r = value_range(k);
    std::vector<float> cube(48 * 48 * 48);
    MinMax mm = evaluate_grid(p, GridRegion::whole(48), cube.data());
    EXPECT_GE(mm.min, r[0]) << kind_name(k);
    EXPECT_LE(mm.max, r[1]) << kind_name(k);
    EXPECT_GT(mm.max - mm.min, 0.2) << kind_name(k);
  }
}

namespace {
// Brute force: every feature point of the tile and of enough neighbouring tile copies.
std::array<double, 2> brute_f1f2(double x, double y, double z, uint32_t P, uint64_t seed) {
  const uint32_t key = detail::seed_key(seed, 0x3a71u);
  const int K = int(std::ceil(3.0 / P)) + 1;
  double f1 = 1e30, f2 = 1e30;
  for (uint32_t cz = 0; cz < P; ++cz)
    for (uint32_t cy = 0; cy < P; ++cy)
      for (uint32_t cx = 0; cx < P; ++cx) {
        uint32_t h = detail::hash3(cx, cy, cz, key);
        double px = cx + detail::jitter01<double>(detail::jitter_hash(h, 0));
        double py = cy + detail::jitter01<double>(detail::jitter_hash(h, 1));
        double pz = cz + detail::jitter01<double>(detail::jitter_hash(h, 2));
        for (int kz = -K; kz <= K; ++kz)
          for (int ky = -K; ky <= K; ++ky)
            for (int kx = -K; kx <= K; ++kx) {
              double dx = px + kx * double(P) - x, dy = py + ky * double(P) - y, dz = pz + kz * double(P) - z;
              double d = std::sqrt(dx * dx + dy * dy + dz * dz);
              if (d < f1) f2 = f1, f1 = d;
              else if (d < f2) f2 = d;
            }
      }
  return {f1, f2};
}
}  // namespace

TEST(Worley, F1AndF2EqualBruteForceOverAllFeaturePoints) {
  for (uint32_t P : {1u, 2u, 4u, 6u}) {
    for (int n = 0; n < 4000; ++n) {
      double x = uni(0, P), y = uni(0, P), z = uni(0, P);
      auto b = brute_f1f2(x, y, z, P, 5 + P);
      WorleyF w = worley(x, y, z, Period::cube(P), 5 + P);
      ASSERT_NEAR(w.f1, b[0], 1e-12) << "P=" << P << " at " << x << "," << y << "," << z;
      ASSERT_NEAR(w.f2, b[1], 1e-12) << "P=" << P << " at " << x << "," << y << "," << z;
      ASSERT_LE(w.f1, kSqrt3);
    }
  }
}

TEST(Worley, ExactSearchFindsWhatA3x3x3SearchMisses) {
  // A plain 3x3x3 search is wrong when every point of the 27 cells is further than a point two
  // cells away. That is rare for uniformly random samples (F1 > 1 at ~0.08% of points), so look
  // where it happens: for every cell and each of the 6 axis directions, put the sample on the cell's
  // face nearest the feature point two cells away. The exact search must find that closer point,
  // and the batch path (3x3x3 fast path plus fallback) must agree with the exact search there.
  const uint32_t P = 32;
  const FractalParams p = fp(Kind::Worley, P, 1, 1);
  const uint64_t seed = detail::octaves(p, Kind::Worley)[0].seed;  // what the batch path hashes
  const uint32_t key = detail::seed_key(seed, 0x3a71u);
  auto feat = [&](int64_t x, int64_t y, int64_t z, double* o) {
    uint32_t h = detail::hash3(detail::wrap(x, P), detail::wrap(y, P), detail::wrap(z, P), key);
    o[0] = x + detail::jitter01<double>(detail::jitter_hash(h, 0));
    o[1] = y + detail::jitter01<double>(detail::jitter_hash(h, 1));
    o[2] = z + detail::jitter01<double>(detail::jitter_hash(h, 2));
  };
  auto naive_f1 = [&](const double* s) {
    int64_t c[3] = {int64_t(std::floor(s[0])), int64_t(std::floor(s[1])), int64_t(std::floor(s[2]))};
    double best = 1e30;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          double f[3];
          feat(c[0] + dx, c[1] + dy, c[2] + dz, f);
          best = std::min(best, std::sqrt((f[0] - s[0]) * (f[0] - s[0]) + (f[1] - s[1]) * (f[1] - s[1]) +
                                          (f[2] - s[2]) * (f[2] - s[2])));
        }
    return best;
  };
  int wrong = 0, batch_checked = 0;
  double worst = 0;
  for (int cz = 0; cz < int(P); ++cz)
    for (int cy = 0; cy < int(P); ++cy)
      for (int cx = 0; cx < int(P); ++cx)
        for (int d = 0; d < 6; ++d) {
          int64_t q[3] = {cx, cy, cz};
          q[d / 2] += (d % 2) ? 2 : -2;
          double qp[3], s[3];
          feat(q[0], q[1], q[2], qp);
          const double c[3] = {double(cx), double(cy), double(cz)};
          for (int a = 0; a < 3; ++a) s[a] = std::clamp(qp[a], c[a] + 1e-3, c[a] + 1 - 1e-3);
          double naive = naive_f1(s), exact = worley(s[0], s[1], s[2], Period::cube(P), seed).f1;
          ASSERT_LE(exact, naive + 1e-12);
          if (exact >= naive - 1e-9) continue;
          ++wrong, worst = std::max(worst, naive - exact);
          if (batch_checked >= 5) continue;
          // The batch path at grid samples right there (grid spacing 1/1024 of a cell).
          ++batch_checked;
          GridRegion r = GridRegion::whole(P * 1024);
          for (int a = 0; a < 3; ++a) r.origin[a] = uint32_t(std::floor(s[a] * 1024)) - 1, r.extent[a] = 3;
          std::vector<double> out(27);
          evaluate_grid(p, r, out.data());
          int fixed = 0;
          for (int n = 0; n < 27; ++n) {
            double t[3] = {(r.origin[0] + n % 3) / 1024.0, (r.origin[1] + n / 3 % 3) / 1024.0,
                           (r.origin[2] + n / 9) / 1024.0};
            double ex = worley(t[0], t[1], t[2], Period::cube(P), seed).f1;
            ASSERT_NEAR(out[n], 1.0 - ex / kSqrt3, 1e-12);
            fixed += naive_f1(t) > ex + 1e-9;
          }
          EXPECT_GT(fixed, 0) << "the grid samples should include 3x3x3 misses";
        }
  EXPECT_GT(wrong, 0) << "expected configurations where 3x3x3 is not enough";
  EXPECT_GT(batch_checked, 0);
  std::printf("  3x3x3 search wrong at %d face points of %u cells, worst F1 error %.4f\n", wrong, P * P * P, worst);
}

// ---------------------------------------------------------------------------------------------
TEST(Batch, MatchesPointEvaluation) {
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley})
    for (uint32_t P : {1u, 3u, 5u, 64u, 1000u}) {
      FractalParams p = fp(k, P, P >= 64 ? 2 : 4, 99);
      GridRegion r;
      r.size = {24, 17, 13};
      std::vector<float> f(r.count());
      std::vector<double> d(r.count());
      evaluate_grid(p, r, f.data());
      evaluate_grid(p, r, d.data());
      for (uint32_t kz = 0; kz < 13; ++kz)
        for (uint32_t j = 0; j < 17; ++j)
          for (uint32_t i = 0; i < 24; ++i) {
            double ref = evaluate(p, double(i) * P / 24, double(j) * P / 17, double(kz) * P / 13);
            size_t q = (size_t(kz) * 17 + j) * 24 + i;
            ASSERT_NEAR(f[q], ref, 1e-6) << kind_name(k) << " P=" << P << " at " << i << "," << j << "," << kz;
            ASSERT_NEAR(d[q], ref, 1e-12) << kind_name(k) << " P=" << P;
          }
    }
}

// High octaves on a tile whose size is a multiple of the period (the usual case: 128 samples,
// periods 8..128) take the Worley kernel's residue-class loop, strides 8, 4, 2 and 1 here, for the
// whole tile and for a box whose origin is not on a cell boundary; it must give the point values.
TEST(Batch, RepeatingLatticeMatchesPointEvaluation) {
  for (Kind k : {Kind::Worley, Kind::PerlinWorley}) {
    FractalParams p = fp(k, 8, 4, 1234);
    GridRegion whole;
    whole.size = {64, 16, 8};
    GridRegion part = whole;
    part.origin = {5, 3, 1};
    part.extent = {45, 7, 5};
    for (const GridRegion& r : {whole, part}) {
      const auto e = r.resolved_extent();
      std::vector<float> f(r.count());
      std::vector<double> d(r.count());
      evaluate_grid(p, r, f.data());
      evaluate_grid(p, r, d.data());
      for (uint32_t kz = 0; kz < e[2]; ++kz)
        for (uint32_t j = 0; j < e[1]; ++j)
          for (uint32_t i = 0; i < e[0]; ++i) {
            const uint32_t x = r.origin[0] + i, y = r.origin[1] + j, z = r.origin[2] + kz;
            double ref = evaluate(p, double(x) * 8 / 64, double(y) * 8 / 16, double(z) * 8 / 8);
            size_t q = (size_t(kz) * e[1] + j) * e[0] + i;
            ASSERT_NEAR(f[q], ref, 1e-6) << kind_name(k) << " at " << x << "," << y << "," << z;
            ASSERT_NEAR(d[q], ref, 1e-12) << kind_name(k) << " at " << x << "," << y << "," << z;
          }
    }
  }
}

TEST(Batch, SubRegionEqualsTheSameSamplesOfTheWholeTile) {
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley}) {
    FractalParams p = fp(k, 4, 3, 5);
    const uint32_t N = 32;
    std::vector<float> whole(N * N * N);
    evaluate_grid(p, GridRegion::whole(N), whole.data());
    GridRegion r = GridRegion::whole(N);
    r.origin = {5, 17, 9};
    r.extent = {11, 8, 20};
    std::vector<float> part(r.count());
    evaluate_grid(p, r, part.data());
    for (uint32_t z = 0; z < 20; ++z)
      for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x = 0; x < 11; ++x)
          ASSERT_EQ(part[(z * 8 + y) * 11 + x], whole[((z + 9) * N + y + 17) * N + x + 5]) << kind_name(k);
  }
}

TEST(PerlinWorley, BlendGoesFromPerlinToPerlinWorley) {
  FractalParams pw = fp(Kind::PerlinWorley, 4, 3, 8), pl = fp(Kind::Perlin, 4, 3, 8);
  for (int n = 0; n < 200; ++n) {
    double x = uni(0, 4), y = uni(0, 4), z = uni(0, 4);
    const double full = evaluate(pw, x, y, z), perlin01 = std::clamp(0.5 + 0.5 * evaluate(pl, x, y, z), 0.0, 1.0);
    pw.blend = 0;
    EXPECT_NEAR(evaluate(pw, x, y, z), perlin01, 1e-12);
    pw.blend = 0.25;
    EXPECT_NEAR(evaluate(pw, x, y, z), perlin01 + 0.25 * (full - perlin01), 1e-12);
    EXPECT_GE(full, perlin01 - 1e-12);  // Worley only dilates
    pw.blend = 1;
  }
  pw.blend = 1.5;
  EXPECT_THROW(validate(pw), InvalidParameter);
}

TEST(Determinism, IdenticalBytesAcrossThreadCountsAndRuns) {
  for (Kind k : {Kind::Perlin, Kind::Worley, Kind::PerlinWorley}) {
    FractalParams p = fp(k, 4, 5, 1234567890123ull);
    const uint32_t N = 40;
    std::vector<float> a(N * N * N), b(N * N * N), c(N * N * N);
    evaluate_grid(p, GridRegion::whole(N), a.data(), BatchOptions{1});
    evaluate_grid(p, GridRegion::whole(N), b.data(), BatchOptions{2});
    evaluate_grid(p, GridRegion::whole(N), c.data(), BatchOptions{1});
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << kind_name(k);
    EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float))) << kind_name(k);
    p.seed += 1;
    evaluate_grid(p, GridRegion::whole(N), c.data());
    EXPECT_NE(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float))) << kind_name(k);
  }
}

// ---------------------------------------------------------------------------------------------
TEST(Curl, IsDivergenceFreeAndTiles) {
  const double h = 1e-4;
  const Period P = Period::cube(6);
  double maxdiv = 0, meanmag = 0;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    double x = uni(0, 6), y = uni(0, 6), z = uni(0, 6);
    auto c = curl(x, y, z, P, 8);
    double div = (curl(x + h, y, z, P, 8)[0] - curl(x - h, y, z, P, 8)[0] + curl(x, y + h, z, P, 8)[1] -
                  curl(x, y - h, z, P, 8)[1] + curl(x, y, z + h, P, 8)[2] - curl(x, y, z - h, P, 8)[2]) /
                 (2 * h);
    maxdiv = std::max(maxdiv, std::fabs(div));
    meanmag += std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / n;
    auto t = curl(x + 6, y - 12, z + 18, P, 8);
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(c[a], t[a], 1e-9);
  }
  EXPECT_GT(meanmag, 0.3);
  EXPECT_LT(maxdiv, 1e-5 * meanmag) << "max |div| " << maxdiv << " vs mean |v| " << meanmag;
}

// ---------------------------------------------------------------------------------------------
TEST(Errors, InvalidParametersNameTheParameterAndRange) {
  auto expect_param = [](auto fn, const std::string& param) {
    try {
      fn();
      ADD_FAILURE() << "no exception for " << param;
    } catch (const InvalidParameter& e) {
      EXPECT_EQ(e.parameter(), param) << e.what();
      EXPECT_NE(std::string(e.what()).find(param), std::string::npos);
    }
  };
  expect_param([] { perlin(0, 0, 0, Period{0, 4, 4}, 1); }, "period.x");
  expect_param([] { worley(0, 0, 0, Period{4, 4, uint32_t(-3)}, 1); }, "period.z");
  expect_param([] { perlin(std::nan(""), 0, 0, Period::cube(4), 1); }, "coordinate.x");
  expect_param([] { worley(0, INFINITY, 0, Period::cube(4), 1); }, "coordinate.y");
  FractalParams p;
  p.octaves = 0;
  expect_param([&] { validate(p); }, "octaves");
  p.octaves = kMaxOctaves + 1;
  expect_param([&] { validate(p); }, "octaves");
  p.octaves = 3;
  p.gain = std::nan("");
  expect_param([&] { validate(p); }, "gain");
  p.gain = 0.5;
  p.lacunarity = 2.5;
  try {
    validate(p);
    ADD_FAILURE();
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "lacunarity");
    EXPECT_NE(std::string(e.what()).find("breaks the wrap"), std::string::npos);
  }
  p.lacunarity = 2;
  p.period = Period::cube(1u << 20);
  p.octaves = 12;  // 2^20 * 2^11 > 2^30
  expect_param([&] { validate(p); }, "octaves");
  expect_param([] { parse_kind("simplex"); }, "kind");
  GridRegion r = GridRegion::whole(8);
  r.origin = {4, 0, 0};
  r.extent = {5, 0, 0};
  std::vector<float> buf(64 * 8);
  expect_param([&] { evaluate_grid(FractalParams{}, r, buf.data()); }, "region.x");
}

// ---------------------------------------------------------------------------------------------
// Pinned values: any change to hashing, gradients, jitter or fBm composition shows up here.
TEST(Golden, PinnedValues) {
  EXPECT_NEAR(perlin_d(0.3, 1.7, 2.2, Period::cube(4), 0), 0.24778102333271046, 1e-12);
  EXPECT_NEAR(perlin_d(12.25, 3.5, 0.125, Period{16, 8, 4}, 42), 0.29437468200922012, 1e-12);
  EXPECT_NEAR(worley(0.3, 1.7, 2.2, Period::cube(4), 0).f1, 0.67782546686868184, 1e-12);
  EXPECT_NEAR(worley(12.25, 3.5, 0.125, Period{16, 8, 4}, 42).f2, 0.77775334766175308, 1e-12);
  EXPECT_NEAR(evaluate(fp(Kind::Perlin, 4, 5, 7), 1.1, 2.2, 3.3), -7.927834343216607e-05, 1e-12);
  EXPECT_NEAR(evaluate(fp(Kind::Worley, 4, 5, 7), 1.1, 2.2, 3.3), 0.65217746957798484, 1e-12);
  EXPECT_NEAR(evaluate(fp(Kind::PerlinWorley, 4, 5, 7), 1.1, 2.2, 3.3), 0.82607494739198228, 1e-12);
}
