// The atmosphere's LUTs on the CPU in double precision (the shared header shaders/atmosphere.glsl
// compiled as C++): the reference of the GPU's passes, and the sky ambient the clouds receive.
#pragma once
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "cloudviewer/atmosphere.h"

namespace cloudviewer {

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
  /// atmosphere_scattering() of atmosphere.glsl: the sky's radiance from altitude `alt` along unit
  /// `v` (zenith +y) with the sun along unit `s` and unit solar irradiance, to the top or the ground
  /// or over the first `t_max` metres (aerial perspective), marched per pixel.
  glm::dvec3 sky_radiance(double alt, const glm::dvec3& v, const glm::dvec3& s, double t_max = CV_NO_HIT) const;
};
AtmosphereLuts compute_atmosphere_luts(const ref::AtmosphereParams& p);

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
