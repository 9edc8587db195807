// The atmosphere's parameters (Bruneton & Neyret's precomputed atmospheric scattering): declared
// once in a table that drives `--set atmosphere.KEY=VALUE`, `--help-params` and
// docs/reference/viewer-params.md, and the std140 block the GL passes read
// (shaders/atmosphere_params.glsl). The CPU LUTs: atmosphere_luts.h.
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
#include "cloudviewer/param_table.h"

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

/// An atmosphere.* parameter (param_table.h).
using AtmosphereParamDef = Param<AtmosphereSettings>;

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

}  // namespace cloudviewer
