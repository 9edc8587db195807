// Phase functions (issue 10): the Lorenz-Mie solver against published values and physical
// identities, the droplet population's features, and the analytic approximations' normalisation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "cloudgen/phase.h"
#include "cloudgen/volume.h"
#include "test_util.h"

using namespace cloudgen;
using namespace cloudgen::phase;

namespace {
std::vector<double> uniform_angles(int n) {
  std::vector<double> a(size_t(n) + 1);
  for (int i = 0; i <= n; ++i) a[size_t(i)] = 180.0 * i / n;
  return a;
}
std::vector<double> cosines(const std::vector<double>& deg) {
  std::vector<double> mu;
  for (double d : deg) mu.push_back(std::cos(d * M_PI / 180));
  return mu;
}
}  // namespace

TEST(Mie, BohrenHuffmanReferenceCase) {
  // Bohren & Huffman's BHMIE example (appendix A): a sphere of radius 0.525 um at 0.6328 um
  // (x = 5.213) with m = 1.55 has Qext = Qsca = 3.10543, Qback = 2.92534, g = 0.63314.
  const double x = 2 * M_PI * 0.525 / 0.6328;
  const MieSphere s = mie_sphere(x, {1.55, 0.0}, {1.0, -1.0});
  EXPECT_NEAR(s.qext, 3.10543, 1e-5);
  EXPECT_NEAR(s.qback, 2.92534, 1e-5);
  EXPECT_NEAR(s.g, 0.63314, 1e-5);
  EXPECT_NEAR(s.qsca, s.qext, 1e-9) << "a non-absorbing sphere scatters all it removes";
  // The optical theorem: Qext = 4 / x^2 Re S(0); |S(0)|^2 >= (x^2 Qext / 4)^2.
  EXPECT_GE(s.intensity[0], std::pow(x * x * s.qext / 4, 2) * (1 - 1e-9));
  // Absorption: Qabs = Qext - Qsca > 0 for k > 0.
  const MieSphere a = mie_sphere(5.213, {1.55, 0.1}, {1.0});
  EXPECT_GT(a.qext - a.qsca, 0.1);
}

TEST(Mie, AngularIntegralEqualsTheSeriesScatteringEfficiency) {
  // Two independent routes to Qsca: the a_n, b_n series, and the scattered intensity integrated
  // over the sphere (Qsca = 1 / (pi x^2) * integral of (|S1|^2 + |S2|^2) / 2 dOmega).
  for (double x : {0.3, 2.0, 12.0, 60.0}) {
    SCOPED_TRACE(x);
    const std::vector<double> deg = uniform_angles(x > 20 ? 72000 : 7200);
    const MieSphere s = mie_sphere(x, {1.333, 0.0}, cosines(deg));
    const double q = sphere_integral(deg, s.intensity) / (M_PI * x * x);
    EXPECT_NEAR(q / s.qsca, 1.0, 2e-4);
    // and the asymmetry parameter from the series equals the one integrated from the angles
    EXPECT_NEAR(asymmetry(deg, s.intensity) / sphere_integral(deg, s.intensity), s.g, 2e-4);
  }
  // Rayleigh limit: Qsca = 8/3 x^4 ((m^2 - 1) / (m^2 + 2))^2 for x << 1.
  const double x = 0.01, m = 1.333, k = (m * m - 1) / (m * m + 2);
  EXPECT_NEAR(mie_sphere(x, {m, 0.0}, {}).qsca / (8.0 / 3 * std::pow(x, 4) * k * k), 1.0, 1e-3);
}

TEST(Mie, ExtinctionEfficiencyTendsToTwoForLargeDroplets) {
  const double q100 = mie_sphere(100, {1.333, 0.0}, {}).qext;
  const double q2000 = mie_sphere(2000, {1.333, 0.0}, {}).qext;
  EXPECT_LT(std::fabs(q2000 - 2), std::fabs(q100 - 2)) << q100 << " " << q2000;
  EXPECT_NEAR(q2000, 2.0, 0.03);
  EXPECT_THROW(mie_sphere(0, {1.333, 0.0}, {}), InputError);
  EXPECT_THROW(mie_sphere(1, {1.333, -0.1}, {}), InputError);
}

TEST(Mie, CloudDropletPopulationHasTheCloudPhaseFeatures) {
  const std::vector<double> deg = table_angles();
  const BulkPhase p = mie_population({10, 0.111, 0}, 550, deg);
  EXPECT_NEAR(sphere_integral(deg, p.value), 1.0, 1e-12);
  EXPECT_NEAR(p.g, 0.86, 0.015) << "the asymmetry of a 10 um cloud is about 0.86";
  EXPECT_NEAR(asymmetry(deg, p.value), p.g, 2e-3) << "the table's own asymmetry matches the series'";
  EXPECT_NEAR(p.qext_effective, 2.0, 0.15);
  auto at = [&](double a) {
    size_t i = size_t(std::lower_bound(deg.begin(), deg.end(), a - 1e-9) - deg.begin());
    return p.value[i];
  };
  EXPECT_GT(at(0) / at(90), 1e4) << "the forward peak is orders of magnitude above the side";
  // The fogbow (cloudbow): a maximum between 135 and 145 degrees, above its surroundings.
  double fog = 0, fog_at = 0;
  for (size_t i = 0; i < deg.size(); ++i)
    if (deg[i] >= 130 && deg[i] <= 150 && p.value[i] > fog) fog = p.value[i], fog_at = deg[i];
  EXPECT_GT(fog_at, 135);
  EXPECT_LT(fog_at, 145);
  EXPECT_GT(fog, 2 * at(125));
  // The glory: a rise toward exact backscatter.
  EXPECT_GT(at(180), 1.5 * at(170));
  EXPECT_THROW(mie_population({0.1, 0.111, 0}, 550, deg), InputError);
}

TEST(PhaseModels, AnalyticModelsIntegrateToOneAndTheFitFollowsMie) {
  const std::vector<double> deg = table_angles();
  auto table = [&](auto f) {
    std::vector<double> v;
    for (double a : deg) v.push_back(f(std::cos(a * M_PI / 180)));
    return v;
  };
  for (double g : {-0.5, 0.0, 0.6, 0.9}) {
    SCOPED_TRACE(g);
    EXPECT_NEAR(sphere_integral(deg, table([&](double c) { return henyey_greenstein(g, c); })), 1.0, 1e-4);
    EXPECT_NEAR(asymmetry(deg, table([&](double c) { return henyey_greenstein(g, c); })), g, 1e-3);
  }
  EXPECT_NEAR(sphere_integral(deg, table([](double c) { return two_lobe_hg(0.8, -0.5, 0.7, c); })), 1.0, 1e-4);
  EXPECT_NEAR(sphere_integral(deg, table([](double c) { return draine(0.6, 27, c); })), 1.0, 1e-4);
  const DraineHgFit f = draine_hg_fit(20);
  const std::vector<double> fit = table([&](double c) { return draine_hg(f, c); });
  EXPECT_NEAR(sphere_integral(deg, fit), 1.0, 1e-3);
  const BulkPhase mie = mie_population({10, 0.111, 0}, 550, deg);
  EXPECT_NEAR(asymmetry(deg, fit), mie.g, 0.03) << "the HG+Draine fit for 20 um droplets has Mie's asymmetry";
  EXPECT_THROW(draine_hg_fit(2), InputError);
}

// Draine's lobe sampled exactly (issue 10: the path tracer weighted its HG proposal by phase / pdf,
// ~6x the noise): the closed-form CDF runs from 0 to 1 and its slope is 2 pi times the lobe, the
// sampler inverts it, and stratified samples reproduce Draine's analytic mean cosine
// g (1 + alpha (3 + 2 g^2) / 5) / (1 + alpha (1 + 2 g^2) / 3) (Draine 2003, eq. 6).
TEST(PhaseModels, DraineLobeIsSampledByItsExactInverseCdf) {
  const DraineHgFit fit = draine_hg_fit(20);
  for (auto [g, alpha] : {std::pair{fit.g_d, fit.alpha}, {0.6, 27.0}, {-0.4, 3.0}, {0.02, 10.0}, {0.0, 1.0}, {0.9, 0.0}}) {
    SCOPED_TRACE("g " + std::to_string(g) + " alpha " + std::to_string(alpha));
    EXPECT_NEAR(draine_cdf(g, alpha, -1), 0.0, 1e-12);
    EXPECT_NEAR(draine_cdf(g, alpha, 1), 1.0, 1e-10);
    for (double c : {-0.9, -0.3, 0.0, 0.4, 0.8, 0.97}) {
      const double h = 1e-5;
      const double slope = (draine_cdf(g, alpha, c + h) - draine_cdf(g, alpha, c - h)) / (2 * h);
      EXPECT_NEAR(slope, 2 * M_PI * draine(g, alpha, c), 1e-5 * (1 + slope)) << "c " << c;
    }
    const int n = 200000;
    double mean = 0, worst = 0;
    for (int i = 0; i < n; ++i) {
      const double u = (i + 0.5) / n, c = sample_draine(g, alpha, u);
      ASSERT_TRUE(c >= -1 && c <= 1) << u;
      worst = std::max(worst, std::fabs(draine_cdf(g, alpha, c) - u));
      mean += c / n;
    }
    EXPECT_LT(worst, 1e-10) << "the sampler inverts the CDF";
    const double want = g * (1 + alpha * (3 + 2 * g * g) / 5) / (1 + alpha * (1 + 2 * g * g) / 3);
    EXPECT_NEAR(mean, want, 1e-4) << "stratified samples give Draine's mean cosine";
  }
}

TEST(PhaseModels, CliWritesTheTableTheRendererReads) {
  testutil::TempDir dir;
  std::string out;
  ASSERT_EQ(testutil::run_cli("phase --model draine-hg --effective-radius 10 -q -o " + (dir / "p.csv"), &out), 0) << out;
  const std::string text = testutil::read_text(dir / "p.csv");
  EXPECT_EQ(text.rfind("angle_deg,r,g,b\n", 0), 0u);
  size_t rows = 0;
  for (char c : text) rows += c == '\n';
  EXPECT_GE(rows - 1, 1801u);
  EXPECT_EQ(testutil::run_cli("phase --model hg --g 1.5 -o " + (dir / "bad.csv"), &out), 1) << out;
  EXPECT_EQ(testutil::run_cli("phase --model nope -o " + (dir / "bad.csv"), &out), 1) << out;
}
