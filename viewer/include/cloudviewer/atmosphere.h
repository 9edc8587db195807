// The atmosphere model (Bruneton & Neyret's precomputed atmospheric scattering): its parameters,
// declared once in a table that drives `--set atmosphere.KEY=VALUE`, `--help-params` and
// docs/viewer.md, the std140 block the GL passes read (shaders/atmosphere_params.glsl), and the
// CPU reference of the LUTs (the shared header shaders/atmosphere.glsl compiled as C++ in double).
#pragma once
#include <array>
#include <functional>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "cloudviewer/constants.h"

namespace cloudviewer {

/// Earth-like defaults of Bruneton's 2017 demo (issue 9). Lengths in metres, coefficients per metre
/// at 680 / 550 / 440 nm (R, G, B).
struct AtmosphereSettings {
  double bottom_radius = 6360e3;
  double top_radius = 6420e3;
  bool rayleigh = true;
  glm::dvec3 rayleigh_scattering{5.802e-6, 13.558e-6, 33.1e-6};
  double rayleigh_height = 8000;
  bool mie = true;
  double mie_extinction = 4.44e-6;
  double mie_scattering = 3.996e-6;
  double mie_height = 1200;
  double mie_g = 0.8;
  bool ozone = true;
  glm::dvec3 ozone_absorption{0.650e-6, 1.881e-6, 0.085e-6};
  double ozone_bottom = 10e3;
  double ozone_peak = 25e3;
  double ozone_top = 40e3;
  double ground_albedo = 0.1;
  double sun_angular_radius_deg = 0.2678;
  int scattering_orders = 4;  ///< 1: single scattering; N: orders 2..N from the multiple-scattering LUT
  /// render.sky_lut: the orders 2..N from Bruneton's scattering-density passes, not Psi_ms.
  bool density_orders = false;
  bool operator==(const AtmosphereSettings& o) const;
  bool operator!=(const AtmosphereSettings& o) const { return !(*this == o); }
};

/// One atmosphere.* parameter (the same shape as the render.* ParamDef, over AtmosphereSettings).
struct AtmosphereParamDef {
  std::string key;    ///< after "atmosphere."
  std::string type;   ///< bool, float
  std::string range;  ///< allowed values, as text
  std::string doc;
  std::function<void(AtmosphereSettings&, const std::string&)> set;  ///< throws InputError
  std::function<std::string(const AtmosphereSettings&)> get;
  double lo = 0, hi = 0;
};

/// The table, in documentation order.
const std::vector<AtmosphereParamDef>& atmosphere_params();
/// Applies one `atmosphere.key=value` (the prefix is optional here). Throws InputError naming the
/// key, the value and what is allowed.
void apply_atmosphere_setting(AtmosphereSettings& s, const std::string& assignment);
/// Checks what single keys cannot: top above bottom, the ozone tent ordered and inside the
/// atmosphere. Throws InputError naming the keys and values.
void validate_atmosphere(const AtmosphereSettings& s);
/// The atmosphere.KEY table as Markdown (docs/viewer.md, `cloudviewer --atmosphere-markdown`).
std::string atmosphere_params_markdown();
/// `--help-params` lines: "  KEY (type, range, default D): doc".
std::string atmosphere_params_help();

namespace gpu {
using Number = float;
using vec3 = glm::vec3;
#include "../../shaders/atmosphere_params.glsl"
}  // namespace gpu
namespace ref {
using Number = double;
using vec3 = glm::dvec3;
#include "../../shaders/atmosphere_params.glsl"
}  // namespace ref
constexpr int kAtmosphereParamsScalars = 28;
static_assert(sizeof(gpu::AtmosphereParams) == kAtmosphereParamsScalars * 4, "std140 AtmosphereBlock size");
static_assert(sizeof(ref::AtmosphereParams) == kAtmosphereParamsScalars * 8, "double AtmosphereParams size");

/// The block's values (constituents turned off get zero coefficients).
ref::AtmosphereParams make_atmosphere_params(const AtmosphereSettings& s);
gpu::AtmosphereParams to_gpu(const ref::AtmosphereParams& d);
/// The double parameters the GPU sees (each value rounded to float).
ref::AtmosphereParams rounded_to_float(const ref::AtmosphereParams& d);

/// Texels of Bruneton's 4D scattering LUT on the CPU (three RGB parts each, keyed by their linear
/// index), computed the first time a lookup reads them and kept: a 160x90 sky reads a few percent
/// of the 2 M texels. Thread-safe.
struct ScatteringTexels {
  std::mutex mutex;
  std::unordered_map<int64_t, std::array<glm::dvec3, 3>> texels;
};

/// The orders table's texture size (8 nu slices of CV_ORDERS_MU_S, CV_ORDERS_MU, CV_ORDERS_R) and a
/// texel's index in it, x fastest.
constexpr int kOrdersNX = CV_SCATTERING_NU * CV_ORDERS_MU_S, kOrdersNY = CV_ORDERS_MU, kOrdersNZ = CV_ORDERS_R;
inline size_t orders_index(const glm::ivec3& t) {
  return (size_t(t.z) * kOrdersNY + size_t(t.y)) * kOrdersNX + size_t(t.x);
}

/// The orders table of atmosphere.density_orders (atmosphere.glsl, orders_dims), computed whole the
/// first time a lookup needs it: the orders 2..N summed, (8 CV_ORDERS_MU_S) x CV_ORDERS_MU x
/// CV_ORDERS_R texels, x fastest, and the time it took.
struct OrdersTable {
  std::once_flag once;
  std::vector<glm::dvec3> sum;
  /// Each order's light on its own, orders 2..min(N, kKeptOrders) (for the tests' checks).
  static constexpr int kKeptOrders = 8;
  std::vector<std::vector<glm::dvec3>> order_light;
  double seconds = 0;
};

/// The atmosphere LUTs as the CPU reference computes them, and the shaders' lookups over them:
/// the transmittance (CV_TRANSMITTANCE_W x CV_TRANSMITTANCE_H), the multiple scattering
/// (CV_MS_LUT_SIZE^2) and the sky's irradiance on the ground (CV_IRRADIANCE_W), RGB, row-major
/// from (0, 0).
struct AtmosphereLuts {
  ref::AtmosphereParams params;
  std::vector<glm::dvec3> transmittance;
  std::vector<glm::dvec3> multiple_scattering;
  std::vector<glm::dvec3> irradiance;
  /// Wall time of each LUT's computation on the CPU (transmittance, multiple scattering, ground
  /// irradiance), seconds (cloudviewer --stats).
  std::array<double, 3> seconds{{0, 0, 0}};
  /// The 4D scattering LUT (render.sky_lut) at the shipped size, filled as the CPU renderer reads it.
  std::shared_ptr<ScatteringTexels> scattering = std::make_shared<ScatteringTexels>();
  /// atmosphere.density_orders: the orders table, computed by orders_sum() on first use.
  std::shared_ptr<OrdersTable> orders = std::make_shared<OrdersTable>();
  /// The orders table's sum (computes it the first time; thread-safe).
  const std::vector<glm::dvec3>& orders_sum() const;
  /// ground_sky_irradiance(mu_s) of atmosphere.glsl: the sky's irradiance on the ground for unit
  /// solar irradiance.
  glm::dvec3 ground_irradiance(double mu_s) const;
  /// transmittance_to_top(r, mu) of atmosphere.glsl (bilinear by hand); rays that hit the ground: 0.
  glm::dvec3 to_top(double r, double mu) const;
  /// transmittance_to_sun(r, mu_s) of atmosphere.glsl: the sunlight's transmittance to radius r
  /// (0 in the Earth's shadow, a smooth set at the horizon).
  glm::dvec3 sun_transmittance(double r, double mu_s) const;
  /// multiple_scattering_at(r, mu_s) of atmosphere.glsl: Psi_ms for unit solar irradiance.
  glm::dvec3 psi_ms(double r, double mu_s) const;
  /// atmosphere_scattering() of atmosphere.glsl: the sky's radiance from altitude `alt` along unit
  /// `v` (zenith +y) with the sun along unit `s` and unit solar irradiance, to the top or the ground
  /// or over the first `t_max` metres (aerial perspective), marched per pixel.
  glm::dvec3 sky_radiance(double alt, const glm::dvec3& v, const glm::dvec3& s, double t_max = CV_NO_HIT) const;
};
AtmosphereLuts compute_atmosphere_luts(const ref::AtmosphereParams& p);

/// For the size-against-error study: the LUT at half (size_index 0), the shipped (1) or double (2)
/// the 256x64 size, computed by the same header, looked up at each (r, mu); `size` receives W x H.
std::vector<glm::dvec3> transmittance_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                      const std::vector<glm::dvec2>& r_mu, glm::ivec2& size);

/// The same study for the multiple-scattering LUT: Psi_ms at (r, mu_s) through the LUT at 16 x 16
/// (size_index 0), the shipped 32 x 32 (1) or 64 x 64 (2); `size` receives the edge.
std::vector<glm::dvec3> multiple_scattering_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                            const std::vector<glm::dvec2>& r_mu_s, int& size);

/// A sky ray for the scattering-LUT study: from `altitude` (m above the ground) along unit `view`
/// (zenith +y) with the sun along unit `sun`, over the first `t_max` metres (CV_NO_HIT: to the top
/// of the atmosphere or the ground).
struct SkyQuery {
  double altitude = 0;
  glm::dvec3 view{0, 1, 0}, sun{0, 1, 0};
  double t_max = CV_NO_HIT;
};
/// Bruneton's 4D scattering LUT (atmosphere.glsl, atmosphere_scattering_lut) on the CPU at half
/// Bruneton's 256 x 128 x 32 (size_index 0: 128 x 64 x 16), his size (1), the shipped size (2: his
/// with twice the mu_s texels, 512 x 128 x 32) or double his (3: 512 x 256 x 64), 8 nu slices
/// each, over the other LUTs of `luts`: the sky's radiance of each query for unit solar
/// irradiance, to the top of the atmosphere or the ground. Texels are computed as lookups read
/// them; `size` receives the 3D texture's size and `texels_computed` how many were computed.
std::vector<glm::dvec3> scattering_lookups_at_size(const AtmosphereLuts& luts, int size_index,
                                                   const std::vector<SkyQuery>& queries, glm::ivec3& size,
                                                   size_t* texels_computed = nullptr);
/// The scattering LUT's parametrisation checked at every texel of the shipped size: the texel's
/// (r, mu, mu_s, nu) mapped back to texture coordinates lands this far (in texels) from the
/// texel's centre, per axis (nu, mu_s, mu, r; nu where the texel's nu is not clamped to what its mu
/// and mu_s allow; mu except the ground rays at r = bottom, which all have length 0).
glm::dvec4 scattering_parametrisation_roundtrip(const AtmosphereLuts& luts);

/// The LUTs of `s` as the renderers use them (parameters rounded to float, what the GPU sees),
/// computed once per distinct atmosphere and shared (thread-safe).
std::shared_ptr<const AtmosphereLuts> shared_atmosphere_luts(const AtmosphereSettings& s);

/// The sky's irradiance at `altitude` (m above the ground) from the upper hemisphere, divided by pi:
/// the isotropic radiance with the same irradiance, the clouds' ambient colour with
/// render.sky=precomputed. `sun_dir` unit, world +y up; `solar`: the sun's irradiance scale.
glm::dvec3 sky_ambient_color(const AtmosphereSettings& s, const glm::dvec3& sun_dir, double solar, double altitude);
/// The same from both halves of the sphere: `above` as sky_ambient_color, `below` the irradiance
/// from the lower hemisphere (the air under the camera and the ground behind it, lit by the sun
/// and the sky) divided by pi.
struct SkyAmbient {
  glm::dvec3 above{0.0}, below{0.0};
};
SkyAmbient sky_ambient(const AtmosphereSettings& s, const glm::dvec3& sun_dir, double solar, double altitude);

/// The --dump-lut grid: kDumpAltitudes altitudes 0..top, kDumpMus values of mu -1..1.
constexpr int kDumpAltitudes = 33;
constexpr int kDumpMus = 129;
/// Row-major (altitude-major) values of the grid, from the CPU LUT.
std::vector<glm::dvec3> transmittance_dump_cpu(const AtmosphereSettings& s);
/// Writes `h_m,mu,r,g,b` rows (a header line, then altitude-major) atomically.
void write_transmittance_csv(const std::string& path, const AtmosphereSettings& s,
                             const std::vector<glm::dvec3>& values);

}  // namespace cloudviewer
