// Tests of the precomputed atmosphere (issue 9): the transmittance LUT of shaders/atmosphere.glsl
// against closed forms and an independent brute-force integration, GL against the CPU reference,
// the atmosphere.* parameter table and `cloudviewer --dump-lut`.
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "cloudviewer/app.h"
#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util_viewer.h"

namespace fs = std::filesystem;
using namespace cloudviewer;

namespace {

// The sky tests' frame: 160x90, or 64x36 under the sanitizers (test_util.h).
const int kW = testutil::kFrameW, kH = testutil::kFrameH;  // 160x90, 64x36 under the sanitizers

using testutil::gl_context;
using testutil::run;

AtmosphereSettings with(std::initializer_list<const char*> sets) {
  RenderSettings s;
  for (const char* a : sets) apply_setting(s, a);
  return s.atmosphere;
}


// Independent of atmosphere.glsl: the ray in Cartesian coordinates, its exit through the top
// sphere from the quadratic, the altitude as |p| - bottom, and composite Simpson with n intervals.
// The atmosphere's coefficients at altitude h from AtmosphereSettings directly (not atmosphere.glsl):
// extinction (Rayleigh + Mie extinction + the ozone tent) and scattering (Rayleigh + Mie), per metre.
glm::dvec3 brute_extinction(const AtmosphereSettings& a, double h) {
  double ozone = h < a.ozone_peak ? (h - a.ozone_bottom) / (a.ozone_peak - a.ozone_bottom)
                                  : (a.ozone_top - h) / (a.ozone_top - a.ozone_peak);
  ozone = std::min(std::max(ozone, 0.0), 1.0);
  return (a.rayleigh ? a.rayleigh_scattering * std::exp(-h / a.rayleigh_height) : glm::dvec3(0.0)) +
         (a.mie ? glm::dvec3(a.mie_extinction * std::exp(-h / a.mie_height)) : glm::dvec3(0.0)) +
         (a.ozone ? a.ozone_absorption * ozone : glm::dvec3(0.0));
}
glm::dvec3 brute_scattering(const AtmosphereSettings& a, double h) {
  return (a.rayleigh ? a.rayleigh_scattering * std::exp(-h / a.rayleigh_height) : glm::dvec3(0.0)) +
         (a.mie ? glm::dvec3(a.mie_scattering * std::exp(-h / a.mie_height)) : glm::dvec3(0.0));
}

glm::dvec3 brute_force_transmittance(const AtmosphereSettings& a, double r, double mu, int n = 20000) {
  glm::dvec3 o(0, r, 0), d(std::sqrt(std::max(0.0, 1 - mu * mu)), mu, 0);
  double b = glm::dot(o, d), c = glm::dot(o, o) - a.top_radius * a.top_radius;
  double t_exit = -b + std::sqrt(std::max(0.0, b * b - c));
  auto sigma = [&](double t) { return brute_extinction(a, glm::length(o + t * d) - a.bottom_radius); };
  glm::dvec3 sum(0.0);
  double dt = t_exit / n;
  for (int i = 0; i <= n; ++i) sum += sigma(i * dt) * ((i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0));
  return glm::exp(-sum * (dt / 3));
}

// Single scattering from altitude alt along unit v with the sun along unit s, unit solar
// irradiance, to the top or the ground: 4000 midpoint samples along the ray, each with the sun's
// transmittance by brute_force_transmittance (200 intervals) and zero in the Earth's shadow;
// Rayleigh and Cornette-Shanks phases written out here.
glm::dvec3 brute_single_scattering(const AtmosphereSettings& a, double alt, const glm::dvec3& v, const glm::dvec3& s) {
  const double bottom = a.bottom_radius, top = a.top_radius;
  glm::dvec3 o(0, bottom + alt, 0);
  double b = glm::dot(o, v), c_top = glm::dot(o, o) - top * top, c_bot = glm::dot(o, o) - bottom * bottom;
  bool ground = b < 0 && b * b - c_bot >= 0;
  double t_end = ground ? -b - std::sqrt(b * b - c_bot) : -b + std::sqrt(std::max(0.0, b * b - c_top));
  double nu = glm::dot(v, s), g = a.mie_g;
  double p_r = 3 / (16 * M_PI) * (1 + nu * nu);
  double p_m = 3 / (8 * M_PI) * (1 - g * g) / (2 + g * g) * (1 + nu * nu) / std::pow(1 + g * g - 2 * g * nu, 1.5);
  const int n = 4000;
  double dt = t_end / n;
  glm::dvec3 tau(0.0), sum(0.0);
  for (int k = 0; k < n; ++k) {
    glm::dvec3 p = o + (k + 0.5) * dt * v;
    double rp = glm::length(p), h = rp - bottom, mu_s = glm::dot(p, s) / rp;
    glm::dvec3 sr = a.rayleigh_scattering * std::exp(-h / a.rayleigh_height);
    double sm = a.mie_scattering * std::exp(-h / a.mie_height);
    glm::dvec3 ext = brute_extinction(a, h);
    bool shadow = mu_s < 0 && rp * rp * (mu_s * mu_s - 1) + bottom * bottom >= 0;
    glm::dvec3 sun = shadow ? glm::dvec3(0.0) : brute_force_transmittance(a, rp, mu_s, 200);
    sum += glm::exp(-(tau + ext * (0.5 * dt))) * (sr * p_r + glm::dvec3(sm * p_m)) * sun * dt;
    tau += ext * dt;
  }
  return sum;
}

// n random sky rays: altitudes 0-20 km (denser low), views over the sphere, the sun from -5 to 90
// degrees at any azimuth.
std::vector<SkyQuery> random_sky_queries(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<SkyQuery> q;
  for (int i = 0; i < n; ++i) {
    SkyQuery k;
    k.altitude = 20000 * std::pow(u01(rng), 2.0);
    double mu = -1 + 2 * u01(rng), phi = 2 * M_PI * u01(rng), st = std::sqrt(1 - mu * mu);
    k.view = glm::dvec3(st * std::cos(phi), mu, st * std::sin(phi));
    k.sun = Sun{360 * u01(rng), -5 + 95 * u01(rng)}.direction();
    q.push_back(k);
  }
  return q;
}

// RMS and worst relative error per channel of `got` against `want`, over the values above 1e-6
// (the sky's light for unit solar irradiance is 1e-3 to 0.1; below 1e-6 is night); n: how many.
struct RelativeError {
  double rms = 0, worst = 0;
  int n = 0;
};
RelativeError relative_error(const std::vector<glm::dvec3>& got, const std::vector<glm::dvec3>& want) {
  RelativeError e;
  double sum2 = 0;
  for (size_t i = 0; i < got.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      if (want[i][c] < 1e-6) continue;
      const double d = got[i][c] / want[i][c] - 1;
      sum2 += d * d, ++e.n;
      e.worst = std::max(e.worst, std::abs(d));
    }
  e.rms = std::sqrt(sum2 / std::max(e.n, 1));
  return e;
}

const PreparedVolume& blob() {
  static PreparedVolume v = prepare_volume(testutil::synthetic("blob"), 8);
  return v;
}

// A frame of the blob with render.sky=precomputed, from `eye` towards `target` (the default camera
// when eye == target), the sun at (azimuth, elevation).
FrameSetup sky_frame(int w, int h, double sun_az, double sun_el, glm::dvec3 eye = glm::dvec3(0.0),
                     glm::dvec3 target = glm::dvec3(0.0), double fov = 60,
                     std::initializer_list<const char*> sets = {}) {
  RenderSettings s;
  apply_setting(s, "render.sky=precomputed");
  apply_setting(s, "render.exact_filter=true");
  apply_setting(s, "render.steps=64");
  apply_setting(s, "render.air_lut=false");  // the sky's own tests study the march and the 4D LUT
  for (const char* a : sets) apply_setting(s, a);
  Camera cam = default_camera(blob(), fov, double(w) / h);
  if (eye != target) cam.eye = eye, cam.target = target, cam.fov_y_deg = fov;
  return make_frame(blob(), s, cam, Sun{sun_az, sun_el}, w, h);
}

// A named view for sky_frame: the sun at (az, el), the camera from eye to target (the default
// camera when equal) with vertical field of view fov.
struct SkyView {
  const char* name;
  double az, el;
  glm::dvec3 eye, target;
  double fov;
};

FrameImages gl_frame(const FrameSetup& f) { return testutil::render_gl(blob(), f); }

glm::dvec3 pixel(const Image& img, int x, int y) {
  const float* p = img.at(x, y);
  return glm::dvec3(p[0], p[1], p[2]);
}

}  // namespace

// The zenith from the ground crosses each exponential layer once: tau_i = beta_i H_i (1 - exp(-Z/H_i))
// with Z = top - bottom; the ozone tent integrates to beta_O (top_O - bottom_O) / 2. The LUT texel
// (0, 0) sits exactly at (bottom, mu = 1), so this measures the precompute's integration alone.
TEST(Atmosphere, ZenithTransmittanceFromTheGroundMatchesTheClosedForm) {
  for (auto sets : std::vector<std::vector<const char*>>{
           {},
           {"atmosphere.mie=false", "atmosphere.ozone=false"},
           {"atmosphere.rayleigh=false", "atmosphere.ozone=false"},
           {"atmosphere.rayleigh=false", "atmosphere.mie=false"},
           {"atmosphere.rayleigh_height=3000", "atmosphere.mie_height=500", "atmosphere.ozone_peak=15000"}}) {
    RenderSettings rs;
    for (const char* a : sets) apply_setting(rs, a);
    const AtmosphereSettings& a = rs.atmosphere;
    double z = a.top_radius - a.bottom_radius;
    glm::dvec3 tau(0.0);
    if (a.rayleigh) tau += a.rayleigh_scattering * a.rayleigh_height * (1 - std::exp(-z / a.rayleigh_height));
    if (a.mie) tau += glm::dvec3(a.mie_extinction * a.mie_height * (1 - std::exp(-z / a.mie_height)));
    if (a.ozone) tau += a.ozone_absorption * (0.5 * (a.ozone_top - a.ozone_bottom));
    glm::dvec3 expect = glm::exp(-tau);
    AtmosphereLuts lut = compute_atmosphere_luts(make_atmosphere_params(a));
    glm::dvec3 got = lut.to_top(a.bottom_radius, 1.0);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(got[c] / expect[c], 1.0, 1e-3) << "channel " << c << " with " << sets.size() << " sets";
    // The same through the GPU texture (float, llvmpipe).
    gl_context();
    GlRenderer r{ShaderSource()};
    std::vector<glm::vec3> gl = r.transmittance_dump(a);
    glm::dvec3 g(gl[size_t(kDumpMus - 1)]);  // altitude 0, mu = 1
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(g[c] / expect[c], 1.0, 1e-3) << "GL channel " << c;
  }
}

// LUT lookups (bilinear over 256x64 texels in Bruneton's parametrisation) against the brute-force
// integral at random (r, mu) whose rays do not hit the ground. Bound: 0.5% relative for
// transmittances above 1e-2 (most of the sky); below that (grazing rays from low altitude) 5e-4
// absolute. Measured (seed 9, 202 rays): 0.40% and 3.4e-5.
TEST(Atmosphere, TransmittanceLookupsMatchABruteForceIntegration) {
  AtmosphereSettings a;
  AtmosphereLuts lut = compute_atmosphere_luts(make_atmosphere_params(a));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int checked = 0;
  double worst_rel = 0, worst_abs = 0;
  for (int k = 0; k < 400; ++k) {
    // Altitudes biased towards the ground (where the air is), mu over the whole sphere.
    double h = (a.top_radius - a.bottom_radius) * std::pow(u01(rng), 2.0);
    double r = a.bottom_radius + h, mu = -1 + 2 * u01(rng);
    double mu_horizon = -std::sqrt(std::max(0.0, 1 - (a.bottom_radius / r) * (a.bottom_radius / r)));
    if (mu < mu_horizon + 1e-4) continue;  // hits the ground (or grazes it)
    glm::dvec3 expect = brute_force_transmittance(a, r, mu);
    glm::dvec3 got = lut.to_top(r, mu);
    for (int c = 0; c < 3; ++c) {
      if (expect[c] > 1e-2) {
        worst_rel = std::max(worst_rel, std::abs(got[c] / expect[c] - 1));
        EXPECT_NEAR(got[c] / expect[c], 1.0, 5e-3) << "h " << h << " mu " << mu << " channel " << c;
      } else {
        worst_abs = std::max(worst_abs, std::abs(got[c] - expect[c]));
        EXPECT_NEAR(got[c], expect[c], 5e-4) << "h " << h << " mu " << mu << " channel " << c;
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 150);
  std::cout << "transmittance LUT vs brute force: " << checked << " rays, worst relative " << worst_rel
            << " (T > 1e-2), worst absolute " << worst_abs << " (T <= 1e-2)\n";
}

// Every entry of the dump grid is finite and in [0, 1], 0 exactly where the ray hits the ground,
// and the GPU's lookup agrees with the CPU reference's (float against double).
TEST(Atmosphere, GlTransmittanceDumpMatchesTheCpuReference) {
  for (auto sets : std::vector<std::vector<const char*>>{{}, {"atmosphere.ozone=false", "atmosphere.mie_height=3000"}}) {
    RenderSettings rs;
    for (const char* a : sets) apply_setting(rs, a);
    std::vector<glm::dvec3> cpu = transmittance_dump_cpu(rs.atmosphere);
    gl_context();
    GlRenderer r{ShaderSource()};
    double ms = -1;
    std::vector<glm::vec3> gl = r.transmittance_dump(rs.atmosphere, &ms);
    EXPECT_GT(ms, 0.0);
    ASSERT_EQ(gl.size(), cpu.size());
    double worst = 0;
    for (size_t i = 0; i < cpu.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(gl[i][c]));
        EXPECT_GE(cpu[i][c], 0.0);
        EXPECT_LE(cpu[i][c], 1.0);
        worst = std::max(worst, std::abs(double(gl[i][c]) - cpu[i][c]));
      }
    EXPECT_LT(worst, 2e-4);
    // Rows at the ground looking down hold 0; looking up from the top of the atmosphere, 1.
    EXPECT_EQ(cpu[0], glm::dvec3(0.0));
    EXPECT_EQ(glm::dvec3(gl[0]), glm::dvec3(0.0));
    glm::dvec3 top_up = cpu[size_t(kDumpAltitudes) * kDumpMus - 1];
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(top_up[c], 1.0, 1e-12);
    // A second dump with the same atmosphere does not recompute.
    r.transmittance_dump(rs.atmosphere, &ms);
    EXPECT_LT(ms, 1e-3);
  }
}

TEST(Atmosphere, ParametersAreSettableAndCheckedWithClearErrors) {
  AtmosphereSettings a = with({"atmosphere.mie_g=0.76", "atmosphere.rayleigh=false", "atmosphere.ground_albedo=0.3"});
  EXPECT_DOUBLE_EQ(a.mie_g, 0.76);
  EXPECT_FALSE(a.rayleigh);
  EXPECT_DOUBLE_EQ(a.ground_albedo, 0.3);
  EXPECT_EQ(make_atmosphere_params(a).rayleigh_scattering_per_m, glm::dvec3(0.0));
  EXPECT_TRUE(AtmosphereSettings() != a);
  // Defaults of the issue (Bruneton's 2017 demo).
  AtmosphereSettings d;
  EXPECT_EQ(d.bottom_radius, 6360e3);
  EXPECT_EQ(d.top_radius, 6420e3);
  EXPECT_EQ(d.rayleigh_scattering, glm::dvec3(5.802e-6, 13.558e-6, 33.1e-6));
  EXPECT_EQ(d.mie_extinction, 4.44e-6);
  EXPECT_EQ(d.mie_scattering, 3.996e-6);
  try {
    with({"atmosphere.mie_g=2"});
    FAIL() << "mie_g=2 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("atmosphere.mie_g=2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("[-0.999, 0.999]"), std::string::npos) << e.what();
  }
  EXPECT_THROW(with({"atmosphere.nope=1"}), InputError);
  EXPECT_THROW(with({"atmosphere.ozone=maybe"}), InputError);
  EXPECT_THROW(validate_atmosphere(with({"atmosphere.top_radius=6000e3"})), InputError);
  EXPECT_THROW(validate_atmosphere(with({"atmosphere.ozone_peak=50000"})), InputError);
  EXPECT_THROW(validate_atmosphere(with({"atmosphere.mie_scattering=5e-6"})), InputError);
  std::string out;
  ASSERT_EQ(run({"--help-params"}, nullptr, &out), 0);
  EXPECT_NE(out.find("mie_g (float, [-0.999, 0.999], default 0.8)"), std::string::npos);
  std::string err;
  EXPECT_EQ(run({"--dump-lut", "transmittance", "--out", "x.csv", "--set", "atmosphere.top_radius=6000e3"}, &err, &out), 1);
  EXPECT_NE(err.find("atmosphere.top_radius"), std::string::npos) << err;
}

TEST(Atmosphere, DumpLutWritesTheDocumentedCsv) {
  fs::path dir = fs::temp_directory_path() / "cloud_tests_atmosphere";
  fs::create_directories(dir);
  for (const char* backend : {"cpu", "gl"}) {
    fs::path csv = dir / (std::string("t_") + backend + ".csv");
    ASSERT_EQ(run({"--dump-lut", "transmittance", "--out", csv.string(), "--backend", backend}), 0) << backend;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "h_m,mu,r,g,b");
    int rows = 0, zero_rows = 0;
    double h = 0, mu = 0, r = 0, g = 0, b = 0;
    char comma;
    while (in >> h >> comma >> mu >> comma >> r >> comma >> g >> comma >> b) {
      ++rows;
      double rad = 6360e3 + h;
      bool hits = mu < 0 && rad * rad * (mu * mu - 1) + 6360e3 * 6360e3 >= 0;
      if (hits) {
        ++zero_rows;
        EXPECT_EQ(r + g + b, 0.0) << h << " " << mu;
      } else {
        EXPECT_GT(r, 0.0) << h << " " << mu;
      }
    }
    EXPECT_EQ(rows, kDumpAltitudes * kDumpMus) << backend;
    EXPECT_GT(zero_rows, 64);
    EXPECT_DOUBLE_EQ(h, 60000.0);
    EXPECT_DOUBLE_EQ(mu, 1.0);
  }
  EXPECT_EQ(run({"--dump-lut", "transmittance"}), 1);  // no --out
  EXPECT_EQ(run({"--dump-lut", "scattering", "--out", "x.csv"}), 1);
}

// docs/reference/viewer-params.md holds the generated atmosphere table (scripts/gen_docs.sh).
TEST(Atmosphere, DocsListTheCurrentParameters) {
  std::ifstream in(std::string(CLOUD_SOURCE_DIR) + "/docs/reference/viewer-params.md");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find(atmosphere_params_markdown()), std::string::npos)
      << "docs/reference/viewer-params.md's atmosphere table is out of date (scripts/gen_docs.sh)";
}

// ---------------------------------------------------------------------------------------- the sky

// GL against the double-precision CPU reference on the same float-rounded parameters (exact
// filtering): the precomputed sky at noon, at sunset and seen from 1000 km, the blob in front.
// Threshold 45 dB (the issue; Bruneton's own model test asserts 47 dB); measured values printed.
TEST(AtmosphereSky, GlMatchesTheCpuReference) {
  for (const SkyView& v : {SkyView{"noon", 0, 60, {}, {}, 60}, SkyView{"sunset", 0, 2, {}, {}, 60},
                           SkyView{"space", 0, 20, {0, 1e6, 0}, {0, 0, -3e6}, 70}}) {
    FrameSetup f = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov);
    FrameImages gl = gl_frame(f);
    FrameImages cpu = render_cpu(blob(), f);
    EXPECT_EQ(image_stats(gl.linear).nonfinite, 0) << v.name;
    double p = psnr(gl.display, cpu.display);
    std::cout << v.name << ": precomputed sky, PSNR GL vs CPU " << p << " dB\n";
    EXPECT_GT(p, 45.0) << v.name;
  }
}

// render.sky_lut: the sky and the aerial perspective read from the 4D scattering LUT, which the GL
// renderer computes in a precompute pass. Against the per-pixel march (the same integrals, no
// interpolation) and against the CPU reference reading the same LUT (texels computed in double as
// the pixels read them): noon, sunset, from space, and from 10 km over the ground (the ground seen
// through 10-60 km of air: the S(x) - T S(p) segment lookups). One renderer for all the views: the
// 4D pass runs once, since none of them changes an atmosphere.* key, and not at all while
// render.sky_lut is off.
TEST(AtmosphereSky, ScatteringLutSkyMatchesTheMarchAndTheCpuReference) {
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(blob());
  for (const SkyView& v : {SkyView{"noon", 0, 60, {}, {}, 60}, SkyView{"sunset", 0, 2, {}, {}, 60},
                           SkyView{"space", 0, 20, {0, 1e6, 0}, {0, 0, -3e6}, 70},
                           SkyView{"10 km", 40, 20, {0, 1e4, 0}, {0, 0, -3e4}, 60}}) {
    FrameSetup march = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov);
    FrameSetup lut = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov, {"render.sky_lut=true"});
    r.render(march);
    FrameImages gl_march = r.read_back();
    r.render(lut);
    FrameImages gl_lut = r.read_back();
    FrameImages cpu_lut = render_cpu(blob(), lut);
    EXPECT_EQ(image_stats(gl_lut.linear).nonfinite, 0) << v.name;
    EXPECT_GE(image_stats(gl_lut.linear).min, 0.0) << v.name;
    const double vs_march = psnr(gl_lut.display, gl_march.display), vs_cpu = psnr(gl_lut.display, cpu_lut.display);
    std::cout << v.name << ": LUT sky, PSNR against the march " << vs_march << " dB, GL vs CPU " << vs_cpu << " dB\n";
    EXPECT_GT(vs_march, 60.0) << v.name;  // measured 71-84 dB
    EXPECT_GT(vs_cpu, 45.0) << v.name;    // the bound; measured 88-119 dB
  }
  EXPECT_EQ(r.lut_computations("atmosphere_scattering"), 1);
  EXPECT_EQ(r.lut_computations("atmosphere_transmittance"), 1);
  // Another viewport and the march: nothing recomputed; an atmosphere key changed with the LUT
  // off: the small LUTs only; the LUT back on: the 4D pass again.
  r.render(sky_frame(64, 36, 0, 30));
  EXPECT_EQ(r.lut_computations("atmosphere_transmittance"), 1);
  FrameSetup hazy = sky_frame(64, 36, 0, 30, {}, {}, 60, {"atmosphere.mie_height=2000"});
  r.render(hazy);
  EXPECT_EQ(r.lut_computations("atmosphere_transmittance"), 2);
  EXPECT_EQ(r.lut_computations("atmosphere_scattering"), 1);
  r.render(sky_frame(64, 36, 0, 30, {}, {}, 60, {"atmosphere.mie_height=2000", "render.sky_lut=true"}));
  EXPECT_EQ(r.lut_computations("atmosphere_scattering"), 2);
  EXPECT_EQ(r.lut_computations("atmosphere_transmittance"), 2);
}

// render.air_lut: the sky and the aerial perspective read from the camera's air LUT (a 3D table
// over view direction and distance for the frame's camera altitude and sun). Against the per-pixel
// march its texels repeat (interpolation is the only difference), and against the CPU reference
// reading the same table (texels computed in double as pixels read them): noon, sunset, and from
// 10 km over the ground (10-60 km of air in front of the ground); from space (above the air) the
// sky is marched, the same image. One renderer: the table is built again when the camera's
// altitude or the sun changes, never when the camera only turns or moves sideways, and not at
// all while render.air_lut is off.
TEST(AtmosphereSky, AirLutSkyMatchesTheMarchAndTheCpuReference) {
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(blob());
  int builds = 0;
  for (const SkyView& v : {SkyView{"noon", 0, 60, {}, {}, 60}, SkyView{"sunset", 0, 2, {}, {}, 60},
                           SkyView{"space", 0, 20, {0, 1e6, 0}, {0, 0, -3e6}, 70},
                           SkyView{"10 km", 40, 20, {0, 1e4, 0}, {0, 0, -3e4}, 60}}) {
    FrameSetup march = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov);
    FrameSetup air = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov, {"render.air_lut=true"});
    r.render(march);
    FrameImages gl_march = r.read_back();
    EXPECT_EQ(r.stats().air_lut_builds, builds) << v.name;  // off: never built
    r.render(air);
    FrameImages gl_air = r.read_back();
    const bool space = std::string(v.name) == "space";
    if (!space) ++builds;  // each view: another altitude or sun
    EXPECT_EQ(r.stats().air_lut_builds, builds) << v.name;
    if (space) {
      EXPECT_EQ(max_abs_diff(gl_air.linear, gl_march.linear), 0.0);
      continue;
    }
    FrameImages cpu_air = render_cpu(blob(), air);
    EXPECT_EQ(image_stats(gl_air.linear).nonfinite, 0) << v.name;
    EXPECT_GE(image_stats(gl_air.linear).min, 0.0) << v.name;
    const double vs_march = psnr(gl_air.display, gl_march.display), vs_cpu = psnr(gl_air.display, cpu_air.display);
    std::cout << v.name << ": air LUT sky, PSNR against the march " << vs_march << " dB, GL vs CPU " << vs_cpu
              << " dB\n";
    EXPECT_GT(vs_march, 55.0) << v.name;  // measured 82, 68, 60 dB
    EXPECT_GT(vs_cpu, 45.0) << v.name;  // the bound for GL against the CPU reference
  }
  // The last view turned and moved sideways at the same altitude: the same table.
  FrameSetup turned = sky_frame(160, 90, 40, 20, {5e3, 1e4, 0}, {-3e4, 0, -1e4}, 60, {"render.air_lut=true"});
  r.render(turned);
  EXPECT_EQ(r.stats().air_lut_builds, builds);
  // Higher, or another sun: built again.
  r.render(sky_frame(160, 90, 40, 20, {5e3, 1.1e4, 0}, {-3e4, 0, -1e4}, 60, {"render.air_lut=true"}));
  EXPECT_EQ(r.stats().air_lut_builds, ++builds);
  r.render(sky_frame(160, 90, 50, 20, {5e3, 1.1e4, 0}, {-3e4, 0, -1e4}, 60, {"render.air_lut=true"}));
  EXPECT_EQ(r.stats().air_lut_builds, ++builds);
  // An atmosphere key: the LUTs and the table again.
  r.render(sky_frame(160, 90, 50, 20, {5e3, 1.1e4, 0}, {-3e4, 0, -1e4}, 60,
                     {"render.air_lut=true", "atmosphere.mie_height=2000"}));
  EXPECT_EQ(r.stats().air_lut_builds, ++builds);
}

// Looking up from the ground (fov 90: the bottom row at the horizon, the top row at the zenith),
// the sun behind the camera: the zenith is blue (B > 1.5 R, B > G > R) and the horizon paler
// (B/R smaller) and brighter.
TEST(AtmosphereSky, NoonSkyIsBlueOverheadAndPaleAtTheHorizon) {
  FrameSetup f = sky_frame(64, 64, 180, 60, {0, 2, 0}, {0, 2 + std::sin(M_PI / 4), -std::cos(M_PI / 4)}, 90,
                           {"render.ground=false", "render.density=0", "render.bloom=0"});
  FrameImages img = render_cpu(blob(), f);
  glm::dvec3 zenith = pixel(img.linear, 32, 63), horizon = pixel(img.linear, 32, 1);
  std::cout << "noon zenith " << zenith.x << " " << zenith.y << " " << zenith.z << ", horizon " << horizon.x << " "
            << horizon.y << " " << horizon.z << "\n";
  EXPECT_GT(zenith.z, 1.5 * zenith.x);
  EXPECT_GT(zenith.z, zenith.y);
  EXPECT_GT(zenith.y, zenith.x);
  EXPECT_LT(horizon.z / horizon.x, 0.8 * zenith.z / zenith.x);
  EXPECT_GT(horizon.x + horizon.y + horizon.z, zenith.x + zenith.y + zenith.z);
}

// With the sun 2 degrees up in front of the camera, the sky a few degrees beside the sun is
// orange-red (R > G > B, R > 2 B), and the sun-lit blob is warmer (R/B) than at noon.
TEST(AtmosphereSky, SunsetSkyNearTheSunIsOrangeAndTheCloudWarmer) {
  Sun sun{0, 2};
  glm::dvec3 d = sun.direction();
  glm::dvec3 eye(0, 2, 0);
  FrameSetup f = sky_frame(64, 64, 0, 2, eye, eye + d, 30, {"render.ground=false", "render.density=0", "render.bloom=0"});
  FrameImages img = render_cpu(blob(), f);
  glm::dvec3 beside = pixel(img.linear, 32 + 10, 32 + 4);  // ~5 degrees right of and ~2 above the sun
  std::cout << "sunset beside the sun " << beside.x << " " << beside.y << " " << beside.z << "\n";
  EXPECT_GT(beside.x, beside.y);
  EXPECT_GT(beside.y, beside.z);
  EXPECT_GT(beside.x, 2.0 * beside.z);
  // The blob from the default camera with the sun behind the viewer (its lit side faces us).
  auto warmth = [](double el) {
    FrameSetup c = sky_frame(64, 36, 180, el, {}, {}, 60, {"render.bloom=0"});
    FrameImages im = render_cpu(blob(), c);
    glm::dvec3 sum(0.0);
    for (int y = 14; y < 22; ++y)
      for (int x = 26; x < 38; ++x) sum += pixel(im.linear, x, y);
    return sum.x / sum.z;
  };
  double noon = warmth(60), sunset = warmth(2);
  std::cout << "cloud R/B at noon " << noon << ", at sunset " << sunset << "\n";
  EXPECT_GT(sunset, 1.3 * noon);
}

// No NaN or infinity for the sun from -20 to 90 degrees and the camera from the ground to 1000 km,
// on both backends.
TEST(AtmosphereSky, FiniteEverywhere) {
  gl_context();
  GlRenderer r{ShaderSource()};  // one renderer across the views, as the window keeps one
  r.set_volume(blob());
  for (double alt : {0.5, 1000.0, 1e5, 1e6})
    for (double el : {-20.0, -5.0, 0.0, 2.0, 30.0, 90.0}) {
      FrameSetup f = sky_frame(24, 16, 30, el, {0, alt, 0}, {0, alt * 0.5, -2 * alt - 100}, 90);
      FrameImages cpu = render_cpu(blob(), f);
      r.render(f);
      FrameImages gl = r.read_back();
      EXPECT_EQ(image_stats(cpu.linear).nonfinite, 0) << "alt " << alt << " sun " << el;
      EXPECT_EQ(image_stats(gl.linear).nonfinite, 0) << "alt " << alt << " sun " << el;
      EXPECT_GE(image_stats(gl.linear).min, 0.0);
    }
}

// Time of day is the sun's elevation: with the sun 5 degrees below the horizon the sky towards it
// still glows (the upper air is sunlit) and is brighter than the sky opposite the sun, which the
// multiple scattering keeps blue and visible (single scattering alone left it at ~6e-7, black).
TEST(AtmosphereSky, TwilightIsNotBlack) {
  Sun sun{0, -5};
  glm::dvec3 d = sun.direction();
  glm::dvec3 eye(0, 2, 0), flat = glm::normalize(glm::dvec3(d.x, 0.15, d.z));
  FrameSetup toward = sky_frame(32, 32, 0, -5, eye, eye + flat, 30, {"render.ground=false", "render.density=0", "render.bloom=0"});
  FrameSetup away = sky_frame(32, 32, 0, -5, eye, eye - glm::dvec3(flat.x, -flat.y, flat.z), 30,
                              {"render.ground=false", "render.density=0", "render.bloom=0"});
  glm::dvec3 a = pixel(render_cpu(blob(), toward).linear, 16, 16);
  glm::dvec3 b = pixel(render_cpu(blob(), away).linear, 16, 16);
  std::cout << "twilight toward the sun " << a.x << " " << a.y << " " << a.z << ", away " << b.x << " " << b.y << " "
            << b.z << "\n";
  EXPECT_GT(a.x + a.y + a.z, 1e-3);
  EXPECT_GT(a.x + a.y + a.z, b.x + b.y + b.z);
  EXPECT_GT(b.x + b.y + b.z, 0.03 * (a.x + a.y + a.z));  // measured 4.9%
  EXPECT_GT(b.z, 1.5 * b.x);                             // blue: measured 2.0x
}

// In the Earth's shadow the clouds get no sunlight: with the ambient term off and the sun 3 degrees
// below the horizon (the blob is a few km up, where the horizon dips ~1.5 degrees), the blob only
// hides what is behind it (the region sums to at most the cloud-free sum); with the sun 10 degrees
// up it adds light.
TEST(AtmosphereSky, CloudsInTheEarthsShadowGetNoSun) {
  auto sum = [](double el, bool clouds) {
    FrameSetup f = sky_frame(48, 27, 180, el, {}, {}, 60,
                             {"render.ambient=0", "render.bloom=0", "render.ground=false",
                              clouds ? "render.density=1" : "render.density=0"});
    FrameImages im = render_cpu(blob(), f);
    glm::dvec3 s(0.0);
    for (int y = 10; y < 17; ++y)
      for (int x = 18; x < 30; ++x) s += pixel(im.linear, x, y);
    return s.x + s.y + s.z;
  };
  double shadow_cloud = sum(-3, true), shadow_sky = sum(-3, false);
  double lit_cloud = sum(10, true), lit_sky = sum(10, false);
  std::cout << "sun -3: cloud " << shadow_cloud << " sky " << shadow_sky << "; sun 10: cloud " << lit_cloud << " sky "
            << lit_sky << "\n";
  EXPECT_LE(shadow_cloud, shadow_sky * (1 + 1e-9));
  EXPECT_GT(lit_cloud - lit_sky, 0.02 * lit_sky);  // measured: +5%
}

// Every atmosphere.* number at both ends of its range (the ones validate_atmosphere accepts): the
// image is finite and non-negative, and one GL renderer kept across the changes matches the CPU
// reference each time, which it only does if it recomputed its LUT when the key changed.
TEST(AtmosphereSky, EveryAtmosphereKeyAtTheEndsOfItsRangeRendersAndRecomputes) {
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(blob());
  int rendered = 0, rejected = 0;
  for (const AtmosphereParamDef& p : atmosphere_params()) {
    std::vector<std::string> values = p.type == "bool" ? std::vector<std::string>{"false", "true"}
                                                       : std::vector<std::string>{std::to_string(p.lo), std::to_string(p.hi)};
    for (const std::string& v : values) {
      std::string set = "atmosphere." + p.key + "=" + v;
      FrameSetup f = sky_frame(24, 16, 0, 10, {}, {}, 60, {"render.bloom=0"});
      apply_setting(f.settings, set);
      try {
        validate_atmosphere(f.settings.atmosphere);
      } catch (const InputError&) {
        ++rejected;  // e.g. top_radius at its minimum, below the bottom
        continue;
      }
      // make_frame again: the ambient colour depends on the atmosphere.
      f = make_frame(blob(), f.settings, f.camera, f.sun, 24, 16);
      FrameImages cpu = render_cpu(blob(), f);
      r.render(f);
      FrameImages gl = r.read_back();
      ImageStats sc = image_stats(cpu.linear), sg = image_stats(gl.linear);
      EXPECT_EQ(sc.nonfinite, 0) << set;
      EXPECT_EQ(sg.nonfinite, 0) << set;
      EXPECT_GE(sg.min, 0.0) << set;
      EXPECT_GT(psnr(gl.display, cpu.display), 45.0) << set;
      ++rendered;
    }
  }
  std::cout << rendered << " atmospheres rendered, " << rejected << " rejected by validate_atmosphere\n";
  EXPECT_GT(rendered, 30);
}

// LUT size against error (the benchmark, on the CPU): half, the shipped and double the
// 256x64 size against the brute-force integral at the same random rays. Bilinear interpolation
// error falls with the texel size, so each doubling must shrink the worst relative error (T > 1e-2).
TEST(Atmosphere, TransmittanceErrorFallsWithLutSize) {
  AtmosphereSettings a;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<glm::dvec2> rays;
  std::vector<glm::dvec3> expect;
  while (rays.size() < 150) {
    double r = a.bottom_radius + (a.top_radius - a.bottom_radius) * std::pow(u01(rng), 2.0), mu = -1 + 2 * u01(rng);
    double mu_horizon = -std::sqrt(std::max(0.0, 1 - (a.bottom_radius / r) * (a.bottom_radius / r)));
    if (mu < mu_horizon + 1e-4) continue;
    rays.push_back({r, mu});
    expect.push_back(brute_force_transmittance(a, r, mu));
  }
  double worst[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    glm::ivec2 size;
    std::vector<glm::dvec3> got = transmittance_lookups_at_size(make_atmosphere_params(a), k, rays, size);
    for (size_t i = 0; i < rays.size(); ++i)
      for (int c = 0; c < 3; ++c)
        if (expect[i][c] > 1e-2) worst[k] = std::max(worst[k], std::abs(got[i][c] / expect[i][c] - 1));
    std::cout << "transmittance LUT " << size.x << "x" << size.y << ": worst relative error " << worst[k] << "\n";
  }
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[2], worst[1]);
}

// The std140 AtmosphereBlock as the driver lays it out equals the C++ struct, member by member
// (the cloud pass reads every member; a member the driver drops is reported as -1 and fails).
TEST(AtmosphereSky, AtmosphereBlockLayoutMatchesTheCppStruct) {
  gl_context();
  GlRenderer r{ShaderSource()};
  EXPECT_EQ(r.atmosphere_block_size(), int(sizeof(gpu::AtmosphereParams)));
#define CV_EXPECT_OFFSET(m) EXPECT_EQ(r.atmosphere_block_offset(#m), int(offsetof(gpu::AtmosphereParams, m))) << #m
  CV_EXPECT_OFFSET(rayleigh_scattering_per_m);
  CV_EXPECT_OFFSET(bottom_radius_m);
  CV_EXPECT_OFFSET(mie_scattering_per_m);
  CV_EXPECT_OFFSET(top_radius_m);
  CV_EXPECT_OFFSET(mie_extinction_per_m);
  CV_EXPECT_OFFSET(rayleigh_scale_height_m);
  CV_EXPECT_OFFSET(ozone_absorption_per_m);
  CV_EXPECT_OFFSET(mie_scale_height_m);
  CV_EXPECT_OFFSET(ground_albedo);
  CV_EXPECT_OFFSET(mie_g);
  CV_EXPECT_OFFSET(ozone_bottom_m);
  CV_EXPECT_OFFSET(ozone_peak_m);
  CV_EXPECT_OFFSET(ozone_top_m);
  CV_EXPECT_OFFSET(sun_angular_radius);
#undef CV_EXPECT_OFFSET
}

// ------------------------------------------------------------------------ multiple scattering

namespace {

// Psi_ms of the second order, independent of atmosphere.glsl: Cartesian marches with the optical
// depth summed along the way, the sunlight's transmittance by brute_force_transmittance (Simpson)
// and a hard Earth's shadow from the ray-sphere test. Directions: the sphere split at the horizon
// (cosine mu_h), n_sky bands over the sky and n_ground over the ground, their midpoints in u with
// mu = mu_h + (1 - mu_h) u^3 (and mu_h - (1 + mu_h) u^3 below), which gathers bands where the
// grazing rays carry most light; n_phi sectors over the half-sphere phi in [0, pi] (the light is
// symmetric about the sun's vertical plane), each counted twice.
glm::dvec3 brute_force_second_order(const AtmosphereSettings& a, double r, double mu_s, int n_sky = 48,
                                    int n_ground = 16, int n_phi = 24, int steps = 100, int sun_intervals = 24) {
  const double bottom = a.bottom_radius, top = a.top_radius;
  auto sigma_s = [&](double h) { return brute_scattering(a, h); };
  auto sigma_t = [&](double h) { return brute_extinction(a, h); };
  auto sunlight = [&](const glm::dvec3& p, const glm::dvec3& s) {
    double rp = glm::length(p), mu = glm::dot(p, s) / rp;
    if (mu < 0 && rp * rp * (mu * mu - 1) + bottom * bottom >= 0) return glm::dvec3(0.0);  // the Earth's shadow
    return brute_force_transmittance(a, rp, mu, sun_intervals);
  };
  const glm::dvec3 o(0, r, 0), s(std::sqrt(std::max(0.0, 1 - mu_s * mu_s)), mu_s, 0);
  const double mu_h = -std::sqrt(std::max(0.0, 1 - (bottom / r) * (bottom / r)));
  // L'(d): the once-scattered light (isotropic phase) and the sunlit ground arriving along -d.
  auto arriving = [&](const glm::dvec3& d) {
    double b = glm::dot(o, d);
    double c_top = glm::dot(o, o) - top * top, c_bot = glm::dot(o, o) - bottom * bottom;
    bool ground = b < 0 && b * b - c_bot >= 0;
    double t_end = ground ? -b - std::sqrt(b * b - c_bot) : -b + std::sqrt(std::max(0.0, b * b - c_top));
    double dt = t_end / steps;
    glm::dvec3 tau(0.0), lum(0.0);
    for (int k = 0; k < steps; ++k) {
      glm::dvec3 p = o + (k + 0.5) * dt * d;
      double h = glm::length(p) - bottom;
      glm::dvec3 ext = sigma_t(h);
      lum += glm::exp(-(tau + ext * (0.5 * dt))) * sigma_s(h) * sunlight(p, s) * dt;
      tau += ext * dt;
    }
    lum /= 4 * M_PI;
    if (ground) {
      glm::dvec3 n = glm::normalize(o + t_end * d);
      lum += glm::exp(-tau) * a.ground_albedo / M_PI * sunlight(n * (bottom + 1e-3), s) * std::max(glm::dot(n, s), 0.0);
    }
    return lum;
  };
  glm::dvec3 sum(0.0);  // int L' dw over the sphere
  for (int part = 0; part < 2; ++part) {
    int n = part == 0 ? n_sky : n_ground;
    double span = part == 0 ? 1 - mu_h : 1 + mu_h;  // the cosine range of the part
    for (int i = 0; i < n; ++i) {
      double u = (i + 0.5) / n, x = u * u * u;
      double mu = part == 0 ? mu_h + span * x : mu_h - span * x;
      double dmu = span * 3 * u * u / n;  // |d mu / d u| du
      double st = std::sqrt(std::max(0.0, 1 - mu * mu));
      for (int j = 0; j < n_phi; ++j) {
        double phi = M_PI * (j + 0.5) / n_phi;
        sum += arriving(glm::dvec3(st * std::cos(phi), mu, st * std::sin(phi))) * (dmu * 2 * M_PI / n_phi);
      }
    }
  }
  return sum / (4 * M_PI);
}

}  // namespace

// The multiple-scattering LUT of the second order (atmosphere.scattering_orders=2: Psi_ms = L2)
// against brute_force_second_order at texel centres (no interpolation) from the ground to 29 km,
// the sun from high to 5.6 degrees below the horizon. Bound: 3% relative where Psi > 1e-3 of its
// largest value here (measured below), 1e-3 of that largest value absolute elsewhere.
TEST(Atmosphere, SecondOrderScatteringLutMatchesABruteForceIntegration) {
  AtmosphereSettings a = with({"atmosphere.scattering_orders=2"});
  AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(a));
  struct Texel { int i, j; };  // mu_s = sign(y) y^2 with y = 2 i / 31 - 1, h = 60 km j / 31
  std::vector<Texel> texels = {{23, 0}, {16, 0}, {18, 1}, {15, 3}, {14, 5}, {29, 15}, {20, 8}};
  std::vector<glm::dvec3> lut, ref;
  double largest = 0;
  for (Texel t : texels) {
    double y = 2.0 * t.i / (CV_MS_LUT_SIZE - 1) - 1.0, mu_s = y < 0 ? -y * y : y * y;
    double r = a.bottom_radius + (a.top_radius - a.bottom_radius) * t.j / (CV_MS_LUT_SIZE - 1);
    lut.push_back(luts.multiple_scattering[size_t(t.j) * CV_MS_LUT_SIZE + size_t(t.i)]);
    ref.push_back(brute_force_second_order(a, r, mu_s));
    largest = std::max(largest, std::max(ref.back().x, std::max(ref.back().y, ref.back().z)));
  }
  double worst = 0, worst_abs = 0;
  for (size_t k = 0; k < texels.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      double l = lut[k][c], b = ref[k][c];
      std::cout << "texel (" << texels[k].i << "," << texels[k].j << ") ch " << c << ": lut " << l << " brute " << b
                << "\n";
      if (b > 1e-3 * largest) worst = std::max(worst, std::abs(l - b) / b);
      else worst_abs = std::max(worst_abs, std::abs(l - b));
    }
  std::cout << "second order: worst relative " << worst << ", worst absolute (small values) " << worst_abs
            << " of largest " << largest << "\n";
  EXPECT_LT(worst, 0.03);
  EXPECT_LT(worst_abs, 1e-3 * largest);
}

// Orders 2..N add light, each less than the one before (the series L2 f^k with f < 1), and
// scattering_orders=1 adds nothing: its LUT is zero and the sky is the single-scattering sky.
TEST(Atmosphere, EachScatteringOrderAddsLessLightThanTheOneBefore) {
  std::vector<glm::dvec3> dirs = {{0, 1, 0}, glm::normalize(glm::dvec3(0, 0.1, -1)), glm::normalize(glm::dvec3(1, 0.3, 0))};
  for (double el : {30.0, 2.0, -4.0}) {
    glm::dvec3 s = Sun{0, el}.direction();
    std::vector<std::vector<glm::dvec3>> sky;  // [order][direction]
    for (int orders : {1, 2, 3, 4, 8}) {
      AtmosphereSettings a = with({("atmosphere.scattering_orders=" + std::to_string(orders)).c_str()});
      AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(a));
      if (orders == 1) {
        for (const glm::dvec3& v : luts.multiple_scattering) ASSERT_EQ(v, glm::dvec3(0.0));
      }
      sky.emplace_back();
      for (const glm::dvec3& v : dirs) sky.back().push_back(luts.sky_radiance(1000, v, s));
    }
    for (size_t d = 0; d < dirs.size(); ++d)
      for (int c = 0; c < 3; ++c) {
        double l1 = sky[0][d][c], l2 = sky[1][d][c], l3 = sky[2][d][c], l4 = sky[3][d][c], l8 = sky[4][d][c];
        EXPECT_GT(l2, l1) << "sun " << el << " dir " << d << " ch " << c;
        EXPECT_LT(l3 - l2, l2 - l1) << "sun " << el << " dir " << d << " ch " << c;
        EXPECT_LT(l4 - l3, l3 - l2) << "sun " << el << " dir " << d << " ch " << c;
        EXPECT_GE(l8, l4) << "sun " << el << " dir " << d << " ch " << c;
        if (d == 0 && c == 2)
          std::cout << "sun " << el << " zenith blue: orders 1 " << l1 << ", 2 " << l2 << ", 3 " << l3 << ", 4 " << l4
                    << ", 8 " << l8 << "\n";
      }
  }
}

// The ground irradiance LUT: the sky's irradiance on the ground against the sunlight's, the sun 60
// degrees up. A first-order estimate for this optically thin atmosphere: of the sunlight E0 mu_s
// crossing the air, 1 - exp(-tau_s / mu_s) is scattered, half of the Rayleigh part downwards
// (its phase function is symmetric) and ~90% of the Mie part (g = 0.8, forward); the direct beam
// keeps exp(-tau / mu_s). The LUT's diffuse fraction must lie within 0.9-1.3x that estimate per
// channel (more light from the higher orders, less from the scattered light's own extinction:
// measured 1.05-1.09x). The LUT lookup also agrees with the clouds' ambient (sky_ambient_color:
// the same sky on a finer, full-circle grid) at the ground to 1%, and multiple scattering raises it.
TEST(Atmosphere, GroundIrradianceLutGivesAClearSkyDiffuseFraction) {
  AtmosphereSettings a;
  AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(a));
  double mu_s = std::sin(60 * M_PI / 180);
  glm::dvec3 sky = luts.ground_irradiance(mu_s);
  glm::dvec3 sun = luts.to_top(a.bottom_radius, mu_s) * mu_s;
  glm::dvec3 fraction = sky / (sky + sun);
  const double depth = a.top_radius - a.bottom_radius;
  glm::dvec3 tau_r = a.rayleigh_scattering * a.rayleigh_height * (1 - std::exp(-depth / a.rayleigh_height));
  double tau_ms = a.mie_scattering * a.mie_height, tau_me = a.mie_extinction * a.mie_height;
  glm::dvec3 tau_o = a.ozone_absorption * ((a.ozone_top - a.ozone_bottom) / 2);
  glm::dvec3 est_sky = 0.5 * (1.0 - glm::exp(-tau_r / mu_s)) + 0.9 * (1 - std::exp(-tau_ms / mu_s));
  glm::dvec3 est_sun = glm::exp(-(tau_r + tau_me + tau_o) / mu_s);
  glm::dvec3 estimate = est_sky / (est_sky + est_sun);
  std::cout << "diffuse fraction at sun 60: " << fraction.x << " " << fraction.y << " " << fraction.z << " (estimate "
            << estimate.x << " " << estimate.y << " " << estimate.z << ")\n";
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(fraction[c], 0.9 * estimate[c]) << c;
    EXPECT_LT(fraction[c], 1.3 * estimate[c]) << c;
  }
  glm::dvec3 s = Sun{0, 60}.direction();
  glm::dvec3 ambient = sky_ambient_color(a, s, 1.0, 0.0) * M_PI;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(sky[c], ambient[c], 0.01 * ambient[c]) << c;
  AtmosphereSettings single = with({"atmosphere.scattering_orders=1"});
  AtmosphereLuts single_luts = compute_atmosphere_luts(make_atmosphere_params(single));
  for (int c = 0; c < 3; ++c) EXPECT_GT(sky[c], 1.05 * single_luts.ground_irradiance(mu_s)[c]) << c;
  // Below the horizon by more than the sun's radius the ground gets only sky light, less than at
  // sunrise, and none once the whole atmosphere above is in the Earth's shadow.
  EXPECT_GT(luts.ground_irradiance(std::sin(-2 * M_PI / 180)).y, 0.0);
  EXPECT_LT(luts.ground_irradiance(std::sin(-2 * M_PI / 180)).y, luts.ground_irradiance(0.0).y);
  EXPECT_EQ(luts.ground_irradiance(-1.0), glm::dvec3(0.0));
}

// Multiple-scattering LUT size against error (docs/sky.md): Psi_ms of the second order through
// LUTs of 16^2, 32^2 (shipped) and 64^2 at 24 random (altitude, sun) points between texel centres,
// against brute_force_second_order (a coarser grid than its default: 0.1% of it). The error falls
// with size; the shipped size is within 5% (measured 4.7%; 16^2 6.5%, 64^2 2.9%, where the
// direction quadrature's ~2% takes over).
TEST(Atmosphere, MultipleScatteringErrorFallsWithLutSize) {
  AtmosphereSettings a = with({"atmosphere.scattering_orders=2"});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<glm::dvec2> points;
  std::vector<glm::dvec3> expect;
  double largest = 0;
  while (points.size() < 24) {
    double r = a.bottom_radius + (a.top_radius - a.bottom_radius) * std::pow(u01(rng), 2.0);
    double mu_s = -0.2 + 1.2 * u01(rng);
    points.push_back({r, mu_s});
    expect.push_back(brute_force_second_order(a, r, mu_s, 24, 8, 12, 60, 16));
    largest = std::max(largest, expect.back().z);
  }
  double worst[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    int size = 0;
    std::vector<glm::dvec3> got = multiple_scattering_lookups_at_size(make_atmosphere_params(a), k, points, size);
    for (size_t i = 0; i < points.size(); ++i)
      for (int c = 0; c < 3; ++c)
        if (expect[i][c] > 1e-2 * largest) worst[k] = std::max(worst[k], std::abs(got[i][c] / expect[i][c] - 1));
    std::cout << "multiple-scattering LUT " << size << "x" << size << ": worst relative error " << worst[k] << "\n";
  }
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[1], 0.05);
}

// Single scattering (atmosphere.scattering_orders=1) of the per-pixel sky march against a brute-
// force integral independent of atmosphere.glsl: 4000 midpoint steps along the view ray in
// Cartesian coordinates (optical depth summed along the way), the sunlight's transmittance by
// Simpson (brute_force_transmittance), a hard Earth's shadow, Rayleigh and Cornette-Shanks phase
// functions, at 60 random (altitude, view, sun) triples from the ground to 20 km, views over the
// whole sphere, the sun from 5 degrees below the horizon to the zenith. The bound is 1%.
TEST(Atmosphere, SingleScatteringMatchesABruteForceIntegration) {
  AtmosphereSettings a = with({"atmosphere.scattering_orders=1"});
  AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(a));
  const double bottom = a.bottom_radius;
  auto brute = [&](double alt, const glm::dvec3& v, const glm::dvec3& s) { return brute_single_scattering(a, alt, v, s); };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double worst = 0, worst_ground = 0;
  for (int i = 0; i < 60; ++i) {
    double alt = 20000 * std::pow(u01(rng), 2.0);
    double mu = -1 + 2 * u01(rng), phi = 2 * M_PI * u01(rng), st = std::sqrt(1 - mu * mu);
    glm::dvec3 v(st * std::cos(phi), mu, st * std::sin(phi));
    glm::dvec3 s = Sun{360 * u01(rng), -5 + 95 * u01(rng)}.direction();
    glm::dvec3 got = luts.sky_radiance(alt, v, s), want = brute(alt, v, s);
    double o_r = bottom + alt;
    bool ground = mu < 0 && o_r * o_r * (mu * mu - 1) + bottom * bottom >= 0;
    for (int c = 0; c < 3; ++c) {
      if (want[c] < 1e-6) continue;  // the Earth's shadow: nothing to compare
      double e = std::abs(got[c] / want[c] - 1);
      (ground ? worst_ground : worst) = std::max(ground ? worst_ground : worst, e);
    }
  }
  std::cout << "single scattering vs brute force: worst relative " << worst << " (rays to the sky), " << worst_ground
            << " (rays to the ground)\n";
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(worst_ground, 0.01);
}

// Bruneton's parametrisation of the 4D scattering LUT inverts itself: every texel's (r, mu, mu_s,
// nu) maps back onto that texel's centre on the mu_s, mu and r axes and, where nu is not clamped to
// what mu and mu_s allow, on nu's (a wrong inverse lands texels away). Measured: 1e-12 texel on
// nu, mu_s and r; 2e-4 on mu, where mu = (H^2 - rho^2 - d^2) / (2 r d) cancels for near-vertical
// rays close to the ground.
TEST(Atmosphere, ScatteringLutParametrisationMapsEachTexelOntoItself) {
  const AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(with({})));
  const glm::dvec4 w = scattering_parametrisation_roundtrip(luts);
  std::cout << "scattering LUT round trip, worst in texels: nu " << w.x << ", mu_s " << w.y << ", mu " << w.z << ", r "
            << w.w << "\n";
  EXPECT_LT(w.x, 1e-6);
  EXPECT_LT(w.y, 1e-6);
  EXPECT_LT(w.z, 1e-3);
  EXPECT_LT(w.w, 1e-6);
}

// The 4D LUT's single scattering (atmosphere.scattering_orders=1) against the brute-force
// integration at 300 random rays, at half Bruneton's size, his 256 x 128 x 32, the shipped
// 512 x 128 x 32 (his with twice the mu_s texels) and double his: the relative error of each
// channel (values below 1e-6, the Earth's shadow, left out), for rays to the sky and rays to the
// ground from 200 m up. Rays to the ground from lower down are short and dim (below 3e-4 of the
// solar irradiance, against 1e-3 to 0.1 for the sky): there the r axis's first interval, from the
// ground to 62 m, is the error (reported, not bounded). Measured: RMS 3.2% / 1.6% / 0.79% / 0.55%,
// worst 48% / 42% / 17% / 12%, the worst all with the sun within 3.5 degrees of the horizon,
// mostly in blue. The bound, single scattering within 1%, holds as an RMS at the shipped
// size (not at Bruneton's: docs/sky.md), and the error falls with the size.
TEST(Atmosphere, ScatteringLutMatchesABruteForceIntegration) {
  const AtmosphereSettings a = with({"atmosphere.scattering_orders=1"});
  const AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(a));
  const std::vector<SkyQuery> q = random_sky_queries(300, 11);
  std::vector<glm::dvec3> want;
  std::vector<bool> low_ground;
  for (const SkyQuery& k : q) {
    want.push_back(brute_single_scattering(a, k.altitude, k.view, k.sun));
    const double r = a.bottom_radius + k.altitude, mu = k.view.y;
    low_ground.push_back(k.altitude < 200 && mu < 0 && r * r * (mu * mu - 1) + a.bottom_radius * a.bottom_radius >= 0);
  }
  double rms[4] = {0, 0, 0, 0};
  for (int size = 0; size < 4; ++size) {
    glm::ivec3 dims(0);
    size_t computed = 0;
    const std::vector<glm::dvec3> got = scattering_lookups_at_size(luts, size, q, dims, &computed);
    double sum2 = 0, worst = 0, worst_low = 0;
    int n = 0, n_low = 0, worst_i = 0;
    for (size_t i = 0; i < q.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        if (want[i][c] < 1e-6) continue;
        const double e = got[i][c] / want[i][c] - 1;
        if (low_ground[i]) {
          worst_low = std::max(worst_low, std::abs(e)), ++n_low;
          continue;
        }
        sum2 += e * e, ++n;
        if (std::abs(e) > worst) worst = std::abs(e), worst_i = int(i);
      }
    rms[size] = std::sqrt(sum2 / std::max(n, 1));
    const SkyQuery& k = q[size_t(worst_i)];
    std::cout << "scattering LUT " << dims.x << "x" << dims.y << "x" << dims.z << " vs brute force: RMS relative "
              << rms[size] << ", worst " << worst << " (alt " << k.altitude << " m, mu " << k.view.y << ", mu_s " << k.sun.y
              << ", nu " << glm::dot(k.view, k.sun) << ") over " << n << " values; rays to the ground from below 200 m: "
              << "worst " << worst_low << " over " << n_low << "; " << computed << " texels computed\n";
  }
  EXPECT_LT(rms[2], 0.01) << "the shipped size";
  for (int size = 1; size < 4; ++size) EXPECT_LT(rms[size], rms[size - 1]) << "the error falls with the LUT size";
}

// All the orders (the default 4): the LUT, which folds orders 2..N into its Rayleigh part divided
// by the Rayleigh phase, against the per-pixel march it is built from (same integrals, same
// multiple-scattering LUT), at 200 random rays to the sky and to the ground from 200 m up, at
// the shipped size. Bound: RMS 1%.
TEST(Atmosphere, ScatteringLutWithAllOrdersMatchesTheMarch) {
  const AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(with({})));
  std::vector<SkyQuery> q;
  for (const SkyQuery& k : random_sky_queries(260, 23)) {
    const double r = luts.params.bottom_radius_m + k.altitude, mu = k.view.y, b = luts.params.bottom_radius_m;
    if (k.altitude < 200 && mu < 0 && r * r * (mu * mu - 1) + b * b >= 0) continue;
    if (q.size() < 200) q.push_back(k);
  }
  glm::ivec3 dims(0);
  std::vector<glm::dvec3> want;
  for (const SkyQuery& k : q) want.push_back(luts.sky_radiance(k.altitude, k.view, k.sun));
  const RelativeError e = relative_error(scattering_lookups_at_size(luts, 2, q, dims), want);
  std::cout << "scattering LUT (all orders) vs the march: RMS relative " << e.rms << ", worst " << e.worst << " over "
            << e.n << " values\n";
  EXPECT_LT(e.rms, 0.01);
}

// Aerial perspective through the LUT: the light the air scatters over the first t metres of a ray,
// Bruneton's S(x) - T(x, p) S(p) from two lookups, against the march over the same segment, at
// random rays (as above) cut at t uniform in 5-95% of the distance to the boundary. The error of a
// difference of two lookups grows where S(p) is nearly S(x) (short segments far from the camera's
// dense air), so the bound is looser than for whole rays. Measured: RMS 3.8%, worst 67%, on a
// twilight ray (sun 4.8 degrees down) grazing the horizon from 8.7 km, where the light is 1/1000 of
// the day's; the only green value off by more than 8%.
TEST(Atmosphere, ScatteringLutSegmentsMatchTheMarch) {
  const AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(with({})));
  const double b = luts.params.bottom_radius_m, top = luts.params.top_radius_m;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<SkyQuery> q;
  for (const SkyQuery& k : random_sky_queries(400, 31)) {
    const double r = b + k.altitude, mu = k.view.y;
    const bool ground = mu < 0 && r * r * (mu * mu - 1) + b * b >= 0;
    if (k.altitude < 200 && ground) continue;
    const double d = ground ? -r * mu - std::sqrt(std::max(0.0, r * r * (mu * mu - 1) + b * b))
                            : -r * mu + std::sqrt(std::max(0.0, r * r * (mu * mu - 1) + top * top));
    SkyQuery s = k;
    s.t_max = d * (0.05 + 0.9 * u01(rng));
    if (q.size() < 200) q.push_back(s);
  }
  glm::ivec3 dims(0);
  std::vector<glm::dvec3> want;
  for (const SkyQuery& k : q) want.push_back(luts.sky_radiance(k.altitude, k.view, k.sun, k.t_max));
  const RelativeError e = relative_error(scattering_lookups_at_size(luts, 2, q, dims), want);
  std::cout << "scattering LUT segments vs the march: RMS relative " << e.rms << ", worst " << e.worst << " over "
            << e.n << " values\n";
  EXPECT_LT(e.rms, 0.05);
}

// The clouds' ambient from both halves of the sphere (sky_ambient): from the ground, every ray
// downwards ends on the ground at once, so the light from below is the ground's radiance,
// albedo / pi x (the sun's irradiance T_sun mu_s + the sky's, from the irradiance LUT), to 1%
// (the two integrate differently: hemisphere quadrature against the LUT). At noon the sky above
// is bluer than the grey ground below (B/R above > B/R below); at night both are ~0.
TEST(Atmosphere, AmbientFromBelowIsTheLitGround) {
  AtmosphereSettings a;
  std::shared_ptr<const AtmosphereLuts> luts = shared_atmosphere_luts(a);
  for (double el : {60.0, 10.0}) {
    glm::dvec3 s = Sun{0, el}.direction();
    SkyAmbient amb = sky_ambient(a, s, 1.0, 0.0);
    double mu_s = s.y;
    glm::dvec3 ground = a.ground_albedo / M_PI *
                        (luts->to_top(a.bottom_radius, mu_s) * mu_s + luts->ground_irradiance(mu_s));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(amb.below[c], ground[c], 0.01 * ground[c]) << "sun " << el << " ch " << c;
    std::cout << "sun " << el << ": ambient above " << amb.above.x << " " << amb.above.y << " " << amb.above.z
              << ", below " << amb.below.x << " " << amb.below.y << " " << amb.below.z << "\n";
    EXPECT_GT(amb.above.z / amb.above.x, amb.below.z / amb.below.x);
  }
  SkyAmbient night = sky_ambient(a, Sun{0, -60}.direction(), 1.0, 0.0);
  EXPECT_LT(night.above.y + night.below.y, 1e-9);
}

// --lighting-json (what cloudgen blender matches): the default view's sun colour at the volume's
// centre is the atmosphere's transmittance there (reddened: R > G > B, below 1), the ambient from
// above is bluer than from below's neutral-ish ground, and with the analytic sky both are the
// constants.
TEST(Atmosphere, LightingJsonGivesTheDefaultViewsSunAndAmbient) {
  const fs::path dir = testutil::test_output_dir("lighting");
  auto read = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args{"synthetic:blob", "--lighting-json", (dir / "l.json").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    std::string err;
    EXPECT_EQ(run(args, &err), 0) << err;
    std::ifstream in(dir / "l.json");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  auto numbers = [](const std::string& text, const std::string& key) {
    std::vector<double> v;
    size_t at = text.find("\"" + key + "\"");
    EXPECT_NE(at, std::string::npos) << key;
    at = text.find('[', at);
    std::stringstream ss(text.substr(at + 1, text.find(']', at) - at - 1));
    for (std::string x; std::getline(ss, x, ',');) v.push_back(std::stod(x));
    return v;
  };
  const std::string pre = read({});
  EXPECT_NE(pre.find("\"precomputed\""), std::string::npos) << pre;
  const std::vector<double> sun = numbers(pre, "sun_color"), above = numbers(pre, "ambient_above"),
                            below = numbers(pre, "ambient_below");
  ASSERT_EQ(sun.size(), 3u);
  EXPECT_LT(sun[0], 1.0);
  EXPECT_GT(sun[0], sun[1]);
  EXPECT_GT(sun[1], sun[2]);
  EXPECT_GT(sun[2], 0.2);
  EXPECT_GT(above[2] / above[0], below[2] / below[0]);
  const std::string ana = read({"--set", "render.sky=analytic"});
  EXPECT_EQ(numbers(ana, "sun_color"), (std::vector<double>{1.0, 0.9599999785423279, 0.8999999761581421}));
  EXPECT_EQ(numbers(ana, "ambient_above"), numbers(ana, "ambient_below"));
}

// --stats reports each atmosphere LUT's precompute time, on the GPU (its pass, on the first frame)
// and on the CPU (the reference's double LUTs), and every pass's GPU time.
TEST(Atmosphere, StatsReportThePrecomputeTimeOfEachLut) {
  const fs::path dir = testutil::test_output_dir("lut_stats");
  std::string out, err;
  ASSERT_EQ(run({"synthetic:blob", "--headless", "--size", "48x27", "--stats", "--out", (dir / "s.png").string()}, &err,
                &out),
            0)
      << err;
  for (const char* want : {"gpu: atmosphere LUTs: transmittance ", " multiple_scattering ", " irradiance ",
                           "cpu: atmosphere LUTs: transmittance ", "gpu passes: atmosphere_transmittance "})
    EXPECT_NE(out.find(want), std::string::npos) << want << "\n" << out;
}

// ------------------------------------------------------------------ atmosphere.density_orders
namespace {

// Rotation taking unit `from` onto unit `to` (Rodrigues), for moving a direction into the frame of
// a point whose zenith is `from`.
glm::dmat3 rotation_onto(const glm::dvec3& from, const glm::dvec3& to) {
  const glm::dvec3 k = glm::cross(from, to);
  const double c = glm::dot(from, to), s = glm::length(k);
  if (s < 1e-12) return c > 0 ? glm::dmat3(1.0) : glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0, 0, -1));
  const glm::dvec3 u = k / s;
  const glm::dmat3 kx(glm::dvec3(0, u.z, -u.y), glm::dvec3(-u.z, 0, u.x), glm::dvec3(u.y, -u.x, 0));
  return glm::dmat3(1.0) + s * kx + (1 - c) * kx * kx;
}

// The light scattered exactly twice reaching altitude `alt` along unit v with the sun along s, unit
// solar irradiance, for the density orders' check. Independent of the orders table: along the view
// ray 24 samples (t = D x^2) with the view transmittance from a Simpson march of brute_extinction;
// at each, the scattering density of order 2 by a quadrature with its pole on the view direction
// (the phase function depends on that angle alone, so the Mie peak is resolved: 40 bands gathered
// forward, theta = pi u^2, times 32 sectors), each direction's once-scattered light from the
// header's single-scattering march (luts: scattering_orders=1; checked against a brute force by
// SingleScatteringMatchesABruteForceIntegration) plus, for directions to the ground, the ground's
// reflection of the direct sun (albedo / pi T_sun mu_s, transmittance by brute_extinction).
glm::dvec3 brute_second_order_along(const AtmosphereSettings& a, const AtmosphereLuts& luts, double alt,
                                    const glm::dvec3& v, const glm::dvec3& s) {
  const double bottom = a.bottom_radius, top = a.top_radius, g = a.mie_g;
  auto segment_depth = [&](const glm::dvec3& p, const glm::dvec3& d, double t, int n) {
    glm::dvec3 sum(0.0);
    const double dt = t / n;
    for (int i = 0; i <= n; ++i)
      sum += brute_extinction(a, glm::length(p + i * dt * d) - bottom) * ((i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0));
    return sum * (dt / 3);
  };
  auto exit_distance = [&](const glm::dvec3& p, const glm::dvec3& d, bool& ground) {
    const double b = glm::dot(p, d), c_bot = glm::dot(p, p) - bottom * bottom, c_top = glm::dot(p, p) - top * top;
    ground = b < 0 && b * b - c_bot >= 0;
    return ground ? -b - std::sqrt(b * b - c_bot) : -b + std::sqrt(std::max(0.0, b * b - c_top));
  };
  auto p_r = [](double nu) { return 3 / (16 * M_PI) * (1 + nu * nu); };
  auto p_m = [&](double nu) {
    return 3 / (8 * M_PI) * (1 - g * g) / (2 + g * g) * (1 + nu * nu) / std::pow(1 + g * g - 2 * g * nu, 1.5);
  };
  const glm::dvec3 o(0, bottom + alt, 0);
  bool view_ground = false;
  const double d_view = exit_distance(o, v, view_ground);
  const glm::dvec3 e1 = glm::normalize(std::abs(v.y) < 0.9 ? glm::cross(v, glm::dvec3(0, 1, 0)) : glm::cross(v, glm::dvec3(1, 0, 0)));
  const glm::dvec3 e2 = glm::cross(v, e1);
  const int n_view = 24, n_theta = 40, n_phi = 32;
  glm::dvec3 total(0.0);
  for (int k = 0; k < n_view; ++k) {
    const double x = (k + 0.5) / n_view, t = d_view * x * x, dt = 2 * x * d_view / n_view;
    const glm::dvec3 y = o + t * v;
    const double r_y = glm::length(y), h = r_y - bottom;
    const glm::dvec3 t_view = glm::exp(-segment_depth(o, v, t, 64));
    const glm::dmat3 to_local = rotation_onto(y / r_y, glm::dvec3(0, 1, 0));
    const glm::dvec3 s_local = to_local * s;
    const glm::dvec3 beta_r = a.rayleigh_scattering * std::exp(-h / a.rayleigh_height);
    const double beta_m = a.mie_scattering * std::exp(-h / a.mie_height);
    glm::dvec3 j(0.0);
    for (int i = 0; i < n_theta; ++i) {
      const double u = (i + 0.5) / n_theta, theta = M_PI * u * u, dtheta = 2 * M_PI * u / n_theta;
      const double ct = std::cos(theta), st = std::sin(theta);
      const glm::dvec3 phase = beta_r * p_r(ct) + glm::dvec3(beta_m * p_m(ct));
      for (int m = 0; m < n_phi; ++m) {
        const double phi = 2 * M_PI * (m + 0.5) / n_phi;
        const glm::dvec3 w = ct * v + st * (std::cos(phi) * e1 + std::sin(phi) * e2);
        glm::dvec3 light = luts.sky_radiance(std::max(h, 0.0), to_local * w, s_local);
        bool ground = false;
        const double d = exit_distance(y, w, ground);
        if (ground) {
          const glm::dvec3 q = y + d * w, n = q / glm::length(q);
          const double mu_s = glm::dot(n, s);
          light += glm::exp(-segment_depth(y, w, d, 32)) * (a.ground_albedo / M_PI) *
                   luts.sun_transmittance(bottom, mu_s) * std::max(mu_s, 0.0);
        }
        j += light * phase * (st * dtheta * (2 * M_PI / n_phi));
      }
    }
    total += t_view * j * dt;
  }
  return total;
}

}  // namespace

// atmosphere.density_orders, the second order: the 4D LUT's orders part (scattering_orders=2 minus
// 1, the single parts being the same) against brute_second_order_along on 12 rays (the ground, 2 and
// 8 km; zenith, 5 degrees up, 30 degrees up, and down from 8 km; the sun at 60, 15 and 3 degrees).
// What is tested: the density's sphere quadrature, the ground bounce, the integral along the ray
// and both tables' interpolation. Bound: RMS 5%, worst 12% (measured below).
TEST(Atmosphere, DensityOrdersSecondOrderMatchesABruteForceIntegral) {
  const AtmosphereSettings a1 = with({"atmosphere.scattering_orders=1", "atmosphere.density_orders=true"});
  const AtmosphereSettings a2 = with({"atmosphere.scattering_orders=2", "atmosphere.density_orders=true"});
  const AtmosphereLuts luts1 = compute_atmosphere_luts(make_atmosphere_params(a1));
  const AtmosphereLuts luts2 = compute_atmosphere_luts(make_atmosphere_params(a2));
  std::vector<SkyQuery> q;
  const double alts[] = {0, 2000, 8000};
  const glm::dvec3 views[] = {{0, 1, 0}, glm::normalize(glm::dvec3(1, 0.0875, 0.3)), glm::normalize(glm::dvec3(-0.5, 0.5, 0.7)),
                              glm::normalize(glm::dvec3(0.2, -0.6, -0.7))};
  const double suns[] = {60, 15, 3};
  for (int i = 0; i < 12; ++i) {
    SkyQuery k;
    k.altitude = views[i % 4].y < 0 ? 8000 : alts[i % 3];
    k.view = views[i % 4];
    k.sun = Sun{40.0 * i, suns[(i / 4) % 3]}.direction();
    q.push_back(k);
  }
  glm::ivec3 dims(0);
  const std::vector<glm::dvec3> l1 = scattering_lookups_at_size(luts1, 2, q, dims);
  const std::vector<glm::dvec3> l2 = scattering_lookups_at_size(luts2, 2, q, dims);
  std::vector<glm::dvec3> got, want;
  for (size_t i = 0; i < q.size(); ++i) {
    got.push_back(l2[i] - l1[i]);
    want.push_back(brute_second_order_along(a1, luts1, q[i].altitude, q[i].view, q[i].sun));
    std::cout << "ray " << i << " alt " << q[i].altitude << " mu " << q[i].view.y << ": order 2 table " << got.back().x
              << " " << got.back().y << " " << got.back().z << ", brute " << want.back().x << " " << want.back().y << " "
              << want.back().z << "\n";
  }
  const RelativeError e = relative_error(got, want);
  std::cout << "density orders, second order vs brute force: RMS " << e.rms << ", worst " << e.worst << " over " << e.n
            << " values (" << luts2.orders->seconds << " s for the orders table)\n";
  EXPECT_GT(e.n, 30);
  EXPECT_LT(e.rms, 0.05);
  EXPECT_LT(e.worst, 0.12);
}

// atmosphere.density_orders: each order adds light, less than the one before, at every texel of
// the orders table where order 2 carries more than 1e-5 of the solar irradiance (day light is
// 1e-3 to 1e-2; deep in the Earth's shadow, near 2e-6, light must go round and order 3 can outweigh
// order 2: counted and printed, not asserted), and the four orders stay near Hillaire's Psi_ms series
// (another method: isotropic orders from a 2D LUT) over 200 random sky rays from 200 m up. Bound:
// the two within 5% RMS (measured below).
TEST(Atmosphere, DensityOrdersAddLessEachOrderAndAgreeWithPsiMs) {
  const AtmosphereLuts luts = compute_atmosphere_luts(make_atmosphere_params(with({"atmosphere.density_orders=true"})));
  const std::vector<glm::dvec3>& sum = luts.orders_sum();
  const std::vector<std::vector<glm::dvec3>>& light = luts.orders->order_light;
  ASSERT_EQ(light.size(), 3u);  // orders 2, 3, 4
  int checked = 0, not_less = 0, twilight_not_less = 0;
  double ratio_sum = 0;
  for (size_t i = 0; i < sum.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double l2 = light[0][i][c], l3 = light[1][i][c], l4 = light[2][i][c];
      ASSERT_GE(l2, 0.0);
      ASSERT_GE(l3, 0.0);
      EXPECT_NEAR(sum[i][c], l2 + l3 + l4, 1e-12);
      if (l2 < 1e-5) {
        twilight_not_less += !(l3 < l2 && l4 < l3);
        continue;
      }
      ++checked;
      not_less += !(l3 < l2 && l4 < l3);
      ratio_sum += l3 / l2;
    }
  std::cout << "density orders: " << checked << " texel values, order 3 / order 2 " << ratio_sum / checked << " on average, "
            << not_less << " not decreasing (below 1e-5: " << twilight_not_less << ")\n";
  EXPECT_GT(checked, 100000);
  EXPECT_EQ(not_less, 0);
  std::vector<SkyQuery> q;
  for (const SkyQuery& k : random_sky_queries(260, 29)) {
    const double r = 6360e3 + k.altitude, mu = k.view.y, b = 6360e3;
    if (k.altitude < 200 && mu < 0 && r * r * (mu * mu - 1) + b * b >= 0) continue;
    if (q.size() < 200) q.push_back(k);
  }
  glm::ivec3 dims(0);
  const std::vector<glm::dvec3> lut = scattering_lookups_at_size(luts, 2, q, dims);
  const AtmosphereLuts psi = compute_atmosphere_luts(make_atmosphere_params(with({})));
  std::vector<glm::dvec3> march;
  for (const SkyQuery& k : q) march.push_back(psi.sky_radiance(k.altitude, k.view, k.sun));
  const RelativeError e = relative_error(lut, march);
  std::cout << "density orders (4) vs the Psi_ms march: RMS relative " << e.rms << ", worst " << e.worst << " over " << e.n
            << " values (orders table " << luts.orders->seconds << " s)\n";
  EXPECT_LT(e.rms, 0.05);
}

// The GL orders passes against the CPU reference's orders table (the same header in double), on
// the sky read from the 4D LUT with atmosphere.density_orders: noon, sunset, from space. Bound: 45
// dB (the issue's). The orders passes run once for the three views, and again when an
// atmosphere.* key changes. Under the sanitizers the CPU half is left out: its orders table runs
// sanitized in Atmosphere.DensityOrdersAddLessEachOrderAndAgreeWithPsiMs, and recomputing it here
// took a minute of the sanitized suite to check numbers the optimised build checks.
TEST(AtmosphereSky, DensityOrdersGlMatchesTheCpuReference) {
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(blob());
  for (const SkyView& v : {SkyView{"noon", 0, 60, {}, {}, 60}, SkyView{"sunset", 0, 2, {}, {}, 60},
                           SkyView{"space", 0, 20, {0, 1e6, 0}, {0, 0, -3e6}, 70}}) {
    FrameSetup f = sky_frame(kW, kH, v.az, v.el, v.eye, v.target, v.fov, {"render.sky_lut=true", "atmosphere.density_orders=true"});
    r.render(f);
    FrameImages gl = r.read_back();
    EXPECT_EQ(image_stats(gl.linear).nonfinite, 0) << v.name;
    EXPECT_GE(image_stats(gl.linear).min, 0.0) << v.name;
    if (testutil::kSanitized) continue;
    FrameImages cpu = render_cpu(blob(), f);
    const double p = psnr(gl.display, cpu.display);
    std::cout << v.name << ": density orders, PSNR GL vs CPU " << p << " dB\n";
    EXPECT_GT(p, 45.0) << v.name;
  }
  EXPECT_EQ(r.lut_computations("atmosphere_orders"), 1);
  r.render(sky_frame(64, 36, 0, 30, {}, {}, 60, {"render.sky_lut=true", "atmosphere.density_orders=true", "atmosphere.mie_g=0.7"}));
  EXPECT_EQ(r.lut_computations("atmosphere_orders"), 2);
  r.render(sky_frame(64, 36, 0, 30, {}, {}, 60, {"render.sky_lut=true"}));
  EXPECT_EQ(r.lut_computations("atmosphere_orders"), 2);
}
