// The CPU reference of the atmosphere LUTs: shaders/atmosphere.glsl compiled as C++ in double
// precision inside a class (as cpu_renderer.cpp does for the cloud headers; Bruneton's
// reference/functions.cc pattern). The atmosphere.* table: scene/atmosphere_params.cpp.
#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/testing.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <unordered_map>
#include <utility>

#include <tbb/parallel_for.h>

#include "cloudgen/output.h"
#include "cloudviewer/errors.h"
#include "cpu/glsl_cpp.h"  // last: defines IN/OUT/INOUT

namespace cloudviewer {

ref::AtmosphereParams make_atmosphere_params(const AtmosphereSettings& s) {
  ref::AtmosphereParams p{};
  p.bottom_radius_m = s.bottom_radius;
  p.top_radius_m = s.top_radius;
  p.rayleigh_scattering_per_m = s.rayleigh ? s.rayleigh_scattering : glm::dvec3(0.0);
  p.rayleigh_scale_height_m = s.rayleigh_height;
  p.mie_scattering_per_m = glm::dvec3(s.mie ? s.mie_scattering : 0.0);
  p.mie_extinction_per_m = glm::dvec3(s.mie ? s.mie_extinction : 0.0);
  p.mie_scale_height_m = s.mie_height;
  p.ozone_absorption_per_m = s.ozone ? s.ozone_absorption : glm::dvec3(0.0);
  p.ground_albedo = glm::dvec3(s.ground_albedo);
  p.mie_g = s.mie_g;
  p.ozone_bottom_m = s.ozone_bottom;
  p.ozone_peak_m = s.ozone_peak;
  p.ozone_top_m = s.ozone_top;
  p.sun_angular_radius = s.sun_angular_radius_deg * M_PI / 180.0;
  p.scattering_orders = s.scattering_orders;
  p.density_orders = s.density_orders ? 1.0 : 0.0;
  return p;
}

gpu::AtmosphereParams to_gpu(const ref::AtmosphereParams& d) {
  gpu::AtmosphereParams f;
  const double* src = reinterpret_cast<const double*>(&d);
  float* dst = reinterpret_cast<float*>(&f);
  for (int i = 0; i < kAtmosphereParamsScalars; ++i) dst[i] = float(src[i]);
  return f;
}

ref::AtmosphereParams rounded_to_float(const ref::AtmosphereParams& d) {
  gpu::AtmosphereParams f = to_gpu(d);
  ref::AtmosphereParams r;
  const float* src = reinterpret_cast<const float*>(&f);
  double* dst = reinterpret_cast<double*>(&r);
  for (int i = 0; i < kAtmosphereParamsScalars; ++i) dst[i] = double(src[i]);
  return r;
}

namespace {

using namespace glm;

// Every lookup atmosphere.glsl makes, each reading nothing (0): a shader class below derives from
// this and defines only the lookups its computation reads.
struct NoAtmosphereTexels {
  CV_GLSL_DOUBLE_TYPES;
  vec3 transmittance_texel(ivec2) const { return vec3(0.0); }
  vec3 multiple_scattering_texel(ivec2) const { return vec3(0.0); }
  vec3 irradiance_texel(int) const { return vec3(0.0); }
  vec3 scattering_texel(ivec3) const { return vec3(0.0); }  // the 4D LUT: ScatteringShader
  vec3 single_mie_texel(ivec3) const { return vec3(0.0); }
  vec3 scattering_multiple_texel(ivec3) const { return vec3(0.0); }
  vec3 air_texel(int, ivec3) const { return vec3(0.0); }  // the camera's air LUT: the CPU renderer's
  vec3 orders_texel(int, ivec3) const { return vec3(0.0); }
  vec3 orders_irradiance_texel(int) const { return vec3(0.0); }
};

// atmosphere.glsl in double precision; the LUT lookup reads `lut` (may be empty while computing).
struct AtmosphereShader : NoAtmosphereTexels {

  const ref::AtmosphereParams& u_atmo;
  const std::vector<glm::dvec3>* lut = nullptr;  // transmittance
  const std::vector<glm::dvec3>* ms = nullptr;   // multiple scattering
  const std::vector<glm::dvec3>* irr = nullptr;  // ground irradiance

  vec3 transmittance_texel(ivec2 t) const { return (*lut)[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }
  vec3 multiple_scattering_texel(ivec2 t) const { return (*ms)[size_t(t.y) * CV_MS_LUT_SIZE + size_t(t.x)]; }
  vec3 irradiance_texel(int t) const { return (*irr)[size_t(t)]; }

#include "../../shaders/atmosphere.glsl"
};

// The same header at other LUT sizes (Num/Den times 256x64), for the size-against-error study only.
template <int Num, int Den>
struct SizedAtmosphereShader : NoAtmosphereTexels {

  const ref::AtmosphereParams& u_atmo;
  const std::vector<glm::dvec3>* lut = nullptr;

#pragma push_macro("CV_TRANSMITTANCE_W")
#pragma push_macro("CV_TRANSMITTANCE_H")
#undef CV_TRANSMITTANCE_W
#undef CV_TRANSMITTANCE_H
#define CV_TRANSMITTANCE_W (256 * Num / Den)
#define CV_TRANSMITTANCE_H (64 * Num / Den)
  static constexpr int W = CV_TRANSMITTANCE_W, H = CV_TRANSMITTANCE_H;
  vec3 transmittance_texel(ivec2 t) const { return (*lut)[size_t(t.y) * W + size_t(t.x)]; }
#include "../../shaders/atmosphere.glsl"
#pragma pop_macro("CV_TRANSMITTANCE_W")
#pragma pop_macro("CV_TRANSMITTANCE_H")
};

template <int Num, int Den>
std::vector<glm::dvec3> sized_lookups(const ref::AtmosphereParams& p, const std::vector<glm::dvec2>& r_mu, glm::ivec2& size) {
  using S = SizedAtmosphereShader<Num, Den>;
  std::vector<glm::dvec3> texels(size_t(S::W) * S::H);
  tbb::parallel_for(0, S::H, [&](int y) {
    S sh{{}, p};
    for (int x = 0; x < S::W; ++x) texels[size_t(y) * S::W + size_t(x)] = sh.compute_transmittance_texel(glm::ivec2(x, y));
  });
  S sh{{}, p, &texels};
  std::vector<glm::dvec3> out;
  for (const glm::dvec2& q : r_mu)
    out.push_back(sh.ray_intersects_ground(q.x, q.y) ? glm::dvec3(0.0) : sh.transmittance_to_top(q.x, q.y));
  size = glm::ivec2(S::W, S::H);
  return out;
}

// The header with the multiple-scattering LUT at N x N texels (the transmittance at its shipped
// size), for the size-against-error study only.
template <int N>
struct SizedMsShader : NoAtmosphereTexels {

  const ref::AtmosphereParams& u_atmo;
  const std::vector<glm::dvec3>* lut = nullptr;
  const std::vector<glm::dvec3>* ms = nullptr;

#pragma push_macro("CV_MS_LUT_SIZE")
#undef CV_MS_LUT_SIZE
#define CV_MS_LUT_SIZE N
  vec3 transmittance_texel(ivec2 t) const { return (*lut)[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }
  vec3 multiple_scattering_texel(ivec2 t) const { return (*ms)[size_t(t.y) * N + size_t(t.x)]; }
#include "../../shaders/atmosphere.glsl"
#pragma pop_macro("CV_MS_LUT_SIZE")
};

template <int N>
std::vector<glm::dvec3> sized_ms_lookups(const ref::AtmosphereParams& p, const std::vector<glm::dvec2>& r_mu_s,
                                         int& size) {
  AtmosphereLuts base = compute_atmosphere_luts(p);
  std::vector<glm::dvec3> texels(static_cast<size_t>(N) * N);
  tbb::parallel_for(0, N, [&](int y) {
    SizedMsShader<N> sh{{}, p, &base.transmittance};
    for (int x = 0; x < N; ++x) texels[size_t(y) * N + size_t(x)] = sh.compute_multiple_scattering_texel(glm::ivec2(x, y));
  });
  SizedMsShader<N> sh{{}, p, &base.transmittance, &texels};
  std::vector<glm::dvec3> out;
  for (const glm::dvec2& q : r_mu_s) out.push_back(sh.multiple_scattering_at(q.x, q.y));
  size = N;
  return out;
}

// The orders passes of atmosphere.density_orders on the CPU: the header over the orders table's
// six parts (single Rayleigh, single Mie, the last order, the density's Rayleigh part, the sum, its Mie part) and the last
// order's ground irradiance, as the GL passes read them.
struct OrdersShader : NoAtmosphereTexels {

  const ref::AtmosphereParams& u_atmo;
  const AtmosphereLuts& base;
  std::array<const std::vector<glm::dvec3>*, 6> part;
  const std::vector<glm::dvec3>* irr_orders;

  vec3 transmittance_texel(ivec2 t) const { return base.transmittance[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }
  vec3 multiple_scattering_texel(ivec2 t) const {
    return base.multiple_scattering[size_t(t.y) * CV_MS_LUT_SIZE + size_t(t.x)];
  }
  vec3 irradiance_texel(int t) const { return base.irradiance[size_t(t)]; }
  vec3 orders_texel(int p, ivec3 t) const { return (*part[size_t(p)])[orders_index(t)]; }
  vec3 orders_irradiance_texel(int t) const { return (*irr_orders)[size_t(t)]; }
#include "../../shaders/atmosphere.glsl"
};

void compute_orders_table(const AtmosphereLuts& base, OrdersTable& out) {
  auto t0 = std::chrono::steady_clock::now();
  const size_t n = size_t(kOrdersNX) * kOrdersNY * kOrdersNZ;
  std::vector<glm::dvec3> single_r(n), single_m(n), delta(n), density_r(n), density_m(n), sum(n, glm::dvec3(0.0));
  std::vector<glm::dvec3> irr(CV_IRRADIANCE_W, glm::dvec3(0.0));
  OrdersShader sh{{}, base.params, base, {{&single_r, &single_m, &delta, &density_r, &sum, &density_m}}, &irr};
  auto each_texel = [&](const std::function<void(const glm::ivec3&, size_t)>& fn) {
    tbb::parallel_for(0, kOrdersNZ * kOrdersNY, [&](int row) {
      const int z = row / kOrdersNY, y = row % kOrdersNY;
      for (int x = 0; x < kOrdersNX; ++x) fn(glm::ivec3(x, y, z), orders_index(glm::ivec3(x, y, z)));
    });
  };
  each_texel([&](const glm::ivec3& t, size_t i) {
    sh.compute_orders_single_texel(t, single_r[i], single_m[i]);
  });
  for (int order = 2; order <= int(base.params.scattering_orders + 0.5); ++order) {
    each_texel([&](const glm::ivec3& t, size_t i) { sh.compute_density_texel(t, order, density_r[i], density_m[i]); });
    // The density above read the irradiance of order - 2; now the one of order - 1 for the next.
    std::vector<glm::dvec3> next(CV_IRRADIANCE_W);
    tbb::parallel_for(0, CV_IRRADIANCE_W, [&](int i) { next[size_t(i)] = sh.compute_orders_irradiance_texel(i, order - 1); });
    irr = next;
    each_texel([&](const glm::ivec3& t, size_t i) { delta[i] = sh.compute_orders_multiple_texel(t); });
    for (size_t i = 0; i < n; ++i) sum[i] += delta[i];
    if (order <= OrdersTable::kKeptOrders) out.order_light.push_back(delta);
  }
  out.sum = std::move(sum);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Bruneton's 4D scattering LUT on the CPU at MuS x Mu x R texels per nu slice (8 slices), over the
// other LUTs of `base`. Its texels are computed the first time a
// lookup reads them (a lookup reads 32 of the 1M; thread-safe), each by the header's
// compute_scattering_texel, so a study of a few hundred rays costs milliseconds.
template <int MuS, int Mu, int R>
struct ScatteringShader : NoAtmosphereTexels {

  using Table = ScatteringTexels;
  const ref::AtmosphereParams& u_atmo;
  const AtmosphereLuts& base;
  Table& table;

#pragma push_macro("CV_SCATTERING_MU_S")
#pragma push_macro("CV_SCATTERING_MU")
#pragma push_macro("CV_SCATTERING_R")
#undef CV_SCATTERING_MU_S
#undef CV_SCATTERING_MU
#undef CV_SCATTERING_R
#define CV_SCATTERING_MU_S MuS
#define CV_SCATTERING_MU Mu
#define CV_SCATTERING_R R
  static constexpr int NX = CV_SCATTERING_NU * CV_SCATTERING_MU_S, NY = CV_SCATTERING_MU, NZ = CV_SCATTERING_R;
  vec3 transmittance_texel(ivec2 t) const { return base.transmittance[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }
  vec3 multiple_scattering_texel(ivec2 t) const {
    return base.multiple_scattering[size_t(t.y) * CV_MS_LUT_SIZE + size_t(t.x)];
  }
  vec3 irradiance_texel(int t) const { return base.irradiance[size_t(t)]; }
  const std::array<glm::dvec3, 3>& lut_texel(ivec3 t) const {
    const int64_t key = (int64_t(t.z) * NY + t.y) * NX + t.x;
    {
      std::lock_guard<std::mutex> lock(table.mutex);
      auto it = table.texels.find(key);
      if (it != table.texels.end()) return it->second;
    }
    std::array<glm::dvec3, 3> v;
    ScatteringShader self{{}, u_atmo, base, table};
    self.compute_scattering_texel(t, v[0], v[1], v[2]);
    std::lock_guard<std::mutex> lock(table.mutex);
    return table.texels.emplace(key, v).first->second;  // unordered_map: references stay valid
  }
  vec3 scattering_texel(ivec3 t) const { return lut_texel(t)[0]; }
  vec3 single_mie_texel(ivec3 t) const { return lut_texel(t)[1]; }
  vec3 scattering_multiple_texel(ivec3 t) const { return lut_texel(t)[2]; }
  vec3 orders_texel(int part, ivec3 t) const { return part == 4 ? base.orders_sum()[orders_index(t)] : vec3(0.0); }
#include "../../shaders/atmosphere.glsl"
#pragma pop_macro("CV_SCATTERING_MU_S")
#pragma pop_macro("CV_SCATTERING_MU")
#pragma pop_macro("CV_SCATTERING_R")
};

template <int MuS, int Mu, int R>
std::vector<glm::dvec3> sized_scattering_lookups(const AtmosphereLuts& base, const std::vector<SkyQuery>& queries,
                                                 glm::ivec3& size, size_t* texels_computed) {
  using S = ScatteringShader<MuS, Mu, R>;
  typename S::Table table;
  S sh{{}, base.params, base, table};
  std::vector<glm::dvec3> out;
  for (const SkyQuery& q : queries) {
    glm::dvec3 transmittance(1.0), ground(0.0);
    double t_end = 0;
    out.push_back(sh.atmosphere_scattering_lut(q.altitude, q.view, q.sun, glm::dvec3(1.0), q.t_max, transmittance,
                                               t_end, ground));
  }
  size = glm::ivec3(S::NX, S::NY, S::NZ);
  if (texels_computed) *texels_computed = table.texels.size();
  return out;
}

}  // namespace

std::vector<glm::dvec3> transmittance_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                      const std::vector<glm::dvec2>& r_mu, glm::ivec2& size) {
  switch (size_index) {
    case 0: return sized_lookups<1, 2>(p, r_mu, size);
    case 1: return sized_lookups<1, 1>(p, r_mu, size);
    case 2: return sized_lookups<2, 1>(p, r_mu, size);
    default: throw std::invalid_argument("transmittance_lookups_at_size: size_index must be 0, 1 or 2");
  }
}

std::vector<glm::dvec3> multiple_scattering_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                            const std::vector<glm::dvec2>& r_mu_s, int& size) {
  switch (size_index) {
    case 0: return sized_ms_lookups<16>(p, r_mu_s, size);
    case 1: return sized_ms_lookups<32>(p, r_mu_s, size);
    case 2: return sized_ms_lookups<64>(p, r_mu_s, size);
    default: throw std::invalid_argument("multiple_scattering_lookups_at_size: size_index must be 0, 1 or 2");
  }
}

std::vector<glm::dvec3> scattering_lookups_at_size(const AtmosphereLuts& luts, int size_index,
                                                   const std::vector<SkyQuery>& queries, glm::ivec3& size,
                                                   size_t* texels_computed) {
  switch (size_index) {
    case 0: return sized_scattering_lookups<16, 64, 16>(luts, queries, size, texels_computed);
    case 1: return sized_scattering_lookups<32, 128, 32>(luts, queries, size, texels_computed);
    case 2:
      return sized_scattering_lookups<CV_SCATTERING_MU_S, CV_SCATTERING_MU, CV_SCATTERING_R>(luts, queries, size,
                                                                                           texels_computed);
    case 3: return sized_scattering_lookups<64, 256, 64>(luts, queries, size, texels_computed);
    default: throw std::invalid_argument("scattering_lookups_at_size: size_index must be 0, 1, 2 or 3");
  }
}

glm::dvec4 scattering_parametrisation_roundtrip(const AtmosphereLuts& luts) {
  using S = ScatteringShader<CV_SCATTERING_MU_S, CV_SCATTERING_MU, CV_SCATTERING_R>;
  S::Table table;
  S sh{{}, luts.params, luts, table};
  glm::dvec4 worst(0.0);
  for (int z = 0; z < S::NZ; ++z)
    for (int y = 0; y < S::NY; ++y)
      for (int x = 0; x < S::NX; ++x) {
        double r = 0, mu = 0, mu_s = 0, nu = 0;
        bool ground = false;
        sh.scattering_texel_geometry(glm::ivec3(x, y, z), r, mu, mu_s, nu, ground);
        const glm::dvec4 uvwz = sh.scattering_uvwz(r, mu, mu_s, nu, ground);
        const int slice = x / CV_SCATTERING_MU_S, i_mu_s = x % CV_SCATTERING_MU_S;
        // In texels of each axis: where the lookup lands against the texel's own centre.
        const double spread = std::sqrt(std::max(0.0, (1 - mu * mu) * (1 - mu_s * mu_s)));
        const double nu_set = 2.0 * slice / (CV_SCATTERING_NU - 1) - 1;
        if (std::abs(nu - nu_set) < 1e-12 && spread > 1e-6)  // nu not clamped
          worst.x = std::max(worst.x, std::abs(uvwz.x * (CV_SCATTERING_NU - 1) - slice));
        worst.y = std::max(worst.y, std::abs(uvwz.y * CV_SCATTERING_MU_S - 0.5 - i_mu_s));
        // At the ground (r texel 0, rho = 0) every ray of the lower half has length 0 and mu = -1:
        // the half collapses onto one texel there (as in Bruneton's table), nothing to invert.
        if (!(ground && z == 0)) worst.z = std::max(worst.z, std::abs(uvwz.z * CV_SCATTERING_MU - 0.5 - y));
        worst.w = std::max(worst.w, std::abs(uvwz.w * CV_SCATTERING_R - 0.5 - z));
      }
  return worst;
}

AtmosphereLuts compute_atmosphere_luts(const ref::AtmosphereParams& p) {
  AtmosphereLuts luts;
  luts.params = p;
  auto t0 = std::chrono::steady_clock::now();
  auto lap = [&](int i) {
    const auto t1 = std::chrono::steady_clock::now();
    luts.seconds[size_t(i)] = std::chrono::duration<double>(t1 - t0).count();
    t0 = t1;
  };
  luts.transmittance.resize(size_t(CV_TRANSMITTANCE_W) * CV_TRANSMITTANCE_H);
  tbb::parallel_for(0, CV_TRANSMITTANCE_H, [&](int y) {
    AtmosphereShader sh{{}, luts.params};
    for (int x = 0; x < CV_TRANSMITTANCE_W; ++x)
      luts.transmittance[size_t(y) * CV_TRANSMITTANCE_W + size_t(x)] = sh.compute_transmittance_texel(glm::ivec2(x, y));
  });
  lap(0);
  luts.multiple_scattering.assign(size_t(CV_MS_LUT_SIZE) * CV_MS_LUT_SIZE, glm::dvec3(0.0));
  if (p.scattering_orders > 1.5)
    tbb::parallel_for(0, CV_MS_LUT_SIZE, [&](int y) {
      AtmosphereShader sh{{}, luts.params, &luts.transmittance};
      for (int x = 0; x < CV_MS_LUT_SIZE; ++x)
        luts.multiple_scattering[size_t(y) * CV_MS_LUT_SIZE + size_t(x)] =
            sh.compute_multiple_scattering_texel(glm::ivec2(x, y));
    });
  lap(1);
  luts.irradiance.assign(CV_IRRADIANCE_W, glm::dvec3(0.0));
  tbb::parallel_for(0, CV_IRRADIANCE_W, [&](int x) {
    AtmosphereShader sh{{}, luts.params, &luts.transmittance, &luts.multiple_scattering, &luts.irradiance};
    luts.irradiance[size_t(x)] = sh.compute_irradiance_texel(x);
  });
  lap(2);
  return luts;
}

const std::vector<glm::dvec3>& AtmosphereLuts::orders_sum() const {
  std::call_once(orders->once, [&] { compute_orders_table(*this, *orders); });
  return orders->sum;
}

glm::dvec3 AtmosphereLuts::to_top(double r, double mu) const {
  AtmosphereShader sh{{}, params, &transmittance, &multiple_scattering, &irradiance};
  if (sh.ray_intersects_ground(r, mu)) return glm::dvec3(0.0);
  return sh.transmittance_to_top(r, mu);
}

glm::dvec3 AtmosphereLuts::sun_transmittance(double r, double mu_s) const {
  AtmosphereShader sh{{}, params, &transmittance, &multiple_scattering, &irradiance};
  return sh.transmittance_to_sun(r, mu_s);
}

glm::dvec3 AtmosphereLuts::ground_irradiance(double mu_s) const {
  AtmosphereShader sh{{}, params, &transmittance, &multiple_scattering, &irradiance};
  return sh.ground_sky_irradiance(mu_s);
}

glm::dvec3 AtmosphereLuts::sky_radiance(double alt, const glm::dvec3& v, const glm::dvec3& s, double t_max) const {
  AtmosphereShader sh{{}, params, &transmittance, &multiple_scattering, &irradiance};
  glm::dvec3 t, g;
  double t_end = 0;
  return sh.atmosphere_scattering(alt, v, s, glm::dvec3(1.0), t_max, t, t_end, g);
}

std::shared_ptr<const AtmosphereLuts> shared_atmosphere_luts(const AtmosphereSettings& s) {
  static std::mutex mutex;
  static AtmosphereSettings last;
  static std::shared_ptr<const AtmosphereLuts> luts;
  std::lock_guard<std::mutex> lock(mutex);
  if (!luts || last != s) {
    luts = std::make_shared<const AtmosphereLuts>(compute_atmosphere_luts(rounded_to_float(make_atmosphere_params(s))));
    last = s;
  }
  return luts;
}

SkyAmbient sky_ambient(const AtmosphereSettings& s, const glm::dvec3& sun_dir, double solar, double altitude) {
  // The window calls this every frame: keep the last answer (a deterministic function of these).
  static std::mutex mutex;
  static AtmosphereSettings last_s;
  static glm::dvec3 last_sun(0.0);
  static SkyAmbient last_value;
  static double last_solar = -1, last_alt = -1;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (last_s == s && last_sun == sun_dir && last_solar == solar && last_alt == altitude) return last_value;
  }
  std::shared_ptr<const AtmosphereLuts> luts = shared_atmosphere_luts(s);
  AtmosphereShader sh{{}, luts->params, &luts->transmittance, &luts->multiple_scattering, &luts->irradiance};
  // Midpoint rule over each hemisphere in (|cos theta|, phi): E = int L |cos theta| d(cos theta) d phi.
  // Below: the air under the camera and the ground (lit by the sun and the sky) behind it.
  const int n_theta = 16, n_phi = 32;
  glm::dvec3 e[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
  for (int half = 0; half < 2; ++half)
    for (int i = 0; i < n_theta; ++i) {
      double c = (i + 0.5) / n_theta, sn = std::sqrt(1 - c * c);
      for (int j = 0; j < n_phi; ++j) {
        double phi = 2 * M_PI * (j + 0.5) / n_phi;
        glm::dvec3 v(sn * std::cos(phi), half == 0 ? c : -c, sn * std::sin(phi)), t, g;
        double t_end = 0;
        glm::dvec3 l = sh.atmosphere_scattering(altitude, v, sun_dir, glm::dvec3(solar), CV_NO_HIT, t, t_end, g);
        e[half] += (l + t * g) * c;
      }
    }
  SkyAmbient out;
  out.above = e[0] * ((1.0 / n_theta) * (2 * M_PI / n_phi)) / M_PI;
  out.below = e[1] * ((1.0 / n_theta) * (2 * M_PI / n_phi)) / M_PI;
  std::lock_guard<std::mutex> lock(mutex);
  last_s = s, last_sun = sun_dir, last_solar = solar, last_alt = altitude, last_value = out;
  return out;
}

glm::dvec3 sky_ambient_color(const AtmosphereSettings& s, const glm::dvec3& sun_dir, double solar, double altitude) {
  return sky_ambient(s, sun_dir, solar, altitude).above;
}

std::vector<glm::dvec3> transmittance_dump_cpu(const AtmosphereSettings& s) {
  AtmosphereSettings single = s;
  single.scattering_orders = 1;  // the transmittance only
  AtmosphereLuts lut = compute_atmosphere_luts(make_atmosphere_params(single));
  std::vector<glm::dvec3> v;
  for (int j = 0; j < kDumpAltitudes; ++j)
    for (int i = 0; i < kDumpMus; ++i) {
      double mu = -1.0 + 2.0 * i / (kDumpMus - 1);
      double h = (s.top_radius - s.bottom_radius) * j / (kDumpAltitudes - 1);
      v.push_back(lut.to_top(s.bottom_radius + h, mu));
    }
  return v;
}

void write_transmittance_csv(const std::string& path, const AtmosphereSettings& s,
                             const std::vector<glm::dvec3>& values) {
  if (values.size() != size_t(kDumpAltitudes) * kDumpMus)
    throw std::logic_error("write_transmittance_csv: expected " + std::to_string(kDumpAltitudes * kDumpMus) + " values");
  cloudgen::atomic_write(path, [&](const std::string& tmp) {
    cloudgen::write_file_stream(tmp, [&](std::ostream& os) {
      os << "h_m,mu,r,g,b\n" << std::setprecision(9);
      for (int j = 0; j < kDumpAltitudes; ++j)
        for (int i = 0; i < kDumpMus; ++i) {
          const glm::dvec3& t = values[size_t(j) * kDumpMus + size_t(i)];
          os << (s.top_radius - s.bottom_radius) * j / (kDumpAltitudes - 1) << ","
             << -1.0 + 2.0 * i / (kDumpMus - 1) << "," << t.x << "," << t.y << "," << t.z << "\n";
        }
    });
  });
}

}  // namespace cloudviewer
