// The species presets (issue 43's library) read as their type, measured on the generated volume:
// cumulus-humilis wider than tall, cumulus-congestus taller than wide, cumulonimbus-incus's anvil
// (its top fifth at least twice as wide as its middle) and flat base, stratocumulus's coverage in
// 60-90% (optical depth >= 1 from below), altocumulus and cirrus thin layers with gaps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "cloudgen/generate.h"
#include "cloudgen/preset.h"
#include "test_util.h"

using namespace cloudgen;

namespace {

/// The cloud's extent: per row y, the width along x (metres) of the voxels with density > 0; and
/// the lowest and highest rows with cloud.
struct Extent {
  std::vector<double> width_x;
  int y0 = -1, y1 = -1;
  double width_max = 0, width_z = 0, height = 0;
  /// Per (x, z) column, the vertical optical depth: sigma_t * voxel_size * the sum of densities.
  std::vector<double> tau;
  /// Fraction of the columns with tau >= t: covered as a view from below sees it (t = 1: 63% of
  /// the light blocked; a thin layer, t = 0.1).
  double covered(double t) const {
    return double(std::count_if(tau.begin(), tau.end(), [t](double c) { return c >= t; })) / double(tau.size());
  }
};

/// `sigma_t`: extinction per metre at density 1 (the viewer's default for the preset as shipped,
/// 0.5 / its voxel size, kept when the sanitizers' run makes the voxels larger).
Extent measure(const Preset& p, double sigma_t = 0) {
  if (!(sigma_t > 0)) sigma_t = 0.5 / p.voxel_size;
  const Volume v = generate(p);
  const std::array<uint32_t, 3> N = v.dims;
  Extent e;
  e.width_x.assign(N[1], 0);
  uint32_t zlo = N[2], zhi = 0;
  std::vector<double> tau = std::vector<double>(size_t(N[0]) * N[2], 0.0);
  for (uint32_t y = 0; y < N[1]; ++y) {
    uint32_t lo = N[0], hi = 0;
    for (uint32_t z = 0; z < N[2]; ++z)
      for (uint32_t x = 0; x < N[0]; ++x)
        if (v.density[v.index(x, y, z)] > 0) {
          lo = std::min(lo, x), hi = std::max(hi, x), zlo = std::min(zlo, z), zhi = std::max(zhi, z);
          tau[size_t(z) * N[0] + x] += sigma_t * p.voxel_size * v.density[v.index(x, y, z)];
        }
    if (lo > hi) continue;
    e.width_x[y] = (hi - lo + 1) * p.voxel_size;
    if (e.y0 < 0) e.y0 = int(y);
    e.y1 = int(y);
    e.width_max = std::max(e.width_max, e.width_x[y]);
  }
  e.width_z = zlo <= zhi ? (zhi - zlo + 1) * p.voxel_size : 0;
  e.height = e.y0 < 0 ? 0 : (e.y1 - e.y0 + 1) * p.voxel_size;
  e.tau = std::move(tau);
  return e;
}

/// A shipped preset, smaller under the sanitizers (same world size, so the same shapes), and the
/// viewer's default extinction of the preset as shipped.
Preset species(const char* name, double* sigma_t = nullptr) {
  Preset p = load_preset(testutil::kPresets + name + ".json");
  if (sigma_t) *sigma_t = 0.5 / p.voxel_size;
  if (testutil::kSanitized) rescale(p, 80);
  return p;
}

}  // namespace

TEST(Species, CumulusHumilisIsWiderThanTall) {
  const Extent e = measure(species("cumulus-humilis"));
  std::printf("  humilis: %.0f m wide (x), %.0f m (z), %.0f m tall\n", e.width_max, e.width_z, e.height);
  EXPECT_GT(e.width_max, 2 * e.height);
  EXPECT_GT(e.width_z, 2 * e.height);
}

TEST(Species, CumulusCongestusIsTallerThanWide) {
  const Extent e = measure(species("cumulus-congestus"));
  std::printf("  congestus: %.0f m wide (x), %.0f m (z), %.0f m tall\n", e.width_max, e.width_z, e.height);
  EXPECT_GT(e.height, 1.3 * e.width_max);
  EXPECT_GT(e.height, 1.3 * e.width_z);
}

// The anvil: the widest row of the cloud's top fifth at least twice the middle row's width; the
// base flat (shape.floor) and the top flat under the tropopause (shape.ceiling).
TEST(Species, CumulonimbusAnvilSpreadsAndItsBaseIsFlat) {
  const Preset p = species("cumulonimbus-incus");
  const Extent e = measure(p);
  const int fifth = (e.y1 - e.y0 + 1) / 5;
  double top = 0;
  for (int y = e.y1 - fifth + 1; y <= e.y1; ++y) top = std::max(top, e.width_x[y]);
  const double middle = e.width_x[(e.y0 + e.y1) / 2];
  std::printf("  incus: %.0f m tall, top fifth %.0f m wide, middle %.0f m (%.2fx)\n", e.height, top, middle, top / middle);
  EXPECT_GE(top, 2 * middle);
  ASSERT_TRUE(p.shape.floor && p.shape.ceiling);
  const double base = p.origin[1] + e.y0 * p.voxel_size, crest = p.origin[1] + (e.y1 + 1) * p.voxel_size;
  EXPECT_GE(base, *p.shape.floor - p.shape.falloff / 2);
  EXPECT_LE(crest, *p.shape.ceiling + p.shape.falloff / 2);
}

TEST(Species, LayersCoverWhatTheirTypeCovers) {
  double sigma_t = 0;
  const Preset strato = species("stratocumulus", &sigma_t);
  const Extent sc = measure(strato, sigma_t);
  std::printf("  stratocumulus: %.0f%% of the columns with tau >= 1\n", 100 * sc.covered(1));
  EXPECT_GE(sc.covered(1), 0.6);
  EXPECT_LE(sc.covered(1), 0.9);
  for (const char* thin : {"altocumulus", "cirrus"}) {
    SCOPED_TRACE(thin);
    const Preset p = species(thin, &sigma_t);
    const Extent e = measure(p, sigma_t);
    std::printf("  %s: %.0f%% of the columns with tau >= 0.1, %.0f%% with tau >= 1, %.0f m thick\n", thin,
                100 * e.covered(0.1), 100 * e.covered(1), e.height);
    EXPECT_GT(e.covered(0.1), 0.2);
    EXPECT_LT(e.covered(0.1), 0.9);
    EXPECT_LT(e.covered(1), 0.1) << "a thin layer";
    EXPECT_LE(e.height, 700);
  }
}
