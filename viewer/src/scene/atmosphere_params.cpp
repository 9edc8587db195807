// The atmosphere.* parameter table (atmosphere.h): declared once, driving `--set atmosphere.KEY=VALUE`,
// `--help-params`, docs/reference/viewer-params.md and the panel. Plain data and checks, no OpenGL
// and no LUT code: part of cloudviewer_params, which cloudgen links too (a preset's view.render may
// set atmosphere.* keys, and `cloudgen generate` checks them with this table).
#include "cloudviewer/atmosphere.h"

#include "cloudgen/help_text.h"
#include "cloudviewer/errors.h"
#include "scene/param_parse.h"

namespace cloudviewer {
namespace {

using param::fmt;

// A member, or a member of a member (a colour channel), as the row builders take it.
#define CV_AT(field) [](auto& s) -> auto& { return s.field; }

template <class At>
AtmosphereParamDef real(const std::string& key, At at, double lo, double hi, const std::string& doc) {
  return param::real<AtmosphereSettings>("atmosphere", key, at, lo, hi, doc);
}
template <class At>
AtmosphereParamDef boolean(const std::string& key, At at, const std::string& doc) {
  return param::boolean<AtmosphereSettings>("atmosphere", key, at, doc);
}
template <class At>
AtmosphereParamDef integer(const std::string& key, At at, int lo, int hi, const std::string& doc) {
  return param::integer<AtmosphereSettings>("atmosphere", key, at, lo, hi, doc);
}

std::vector<AtmosphereParamDef> build() {
  std::vector<AtmosphereParamDef> t;
  t.push_back(real("bottom_radius", CV_AT(bottom_radius), 1e3, 1e9, "planet radius (the ground), m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("top_radius", CV_AT(top_radius), 1e3, 1e9, "radius of the top of the atmosphere, m (> bottom_radius)").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(boolean("rayleigh", CV_AT(rayleigh), "Rayleigh scattering (air molecules) on").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("rayleigh_r", CV_AT(rayleigh_scattering.x), 0, 1e-3, "Rayleigh scattering at sea level, 680 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("rayleigh_g", CV_AT(rayleigh_scattering.y), 0, 1e-3, "Rayleigh scattering at sea level, 550 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("rayleigh_b", CV_AT(rayleigh_scattering.z), 0, 1e-3, "Rayleigh scattering at sea level, 440 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("rayleigh_height", CV_AT(rayleigh_height), 1, 1e6, "Rayleigh density scale height (density exp(-h/H)), m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(boolean("mie", CV_AT(mie), "Mie scattering and absorption (aerosols) on").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("mie_extinction", CV_AT(mie_extinction), 0, 1e-2, "Mie extinction at sea level (all wavelengths), 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("mie_scattering", CV_AT(mie_scattering), 0, 1e-2, "Mie scattering at sea level (<= extinction), 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("mie_height", CV_AT(mie_height), 1, 1e6, "Mie density scale height, m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("mie_g", CV_AT(mie_g), -0.999, 0.999, "Mie phase asymmetry (Cornette-Shanks)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(boolean("ozone", CV_AT(ozone), "ozone absorption on").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("ozone_r", CV_AT(ozone_absorption.x), 0, 1e-3, "ozone absorption at the peak, 680 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ozone_g", CV_AT(ozone_absorption.y), 0, 1e-3, "ozone absorption at the peak, 550 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ozone_b", CV_AT(ozone_absorption.z), 0, 1e-3, "ozone absorption at the peak, 440 nm, 1/m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ozone_bottom", CV_AT(ozone_bottom), 0, 1e6, "ozone tent profile: zero below this altitude, m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ozone_peak", CV_AT(ozone_peak), 0, 1e6, "ozone tent profile: density 1 at this altitude, m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ozone_top", CV_AT(ozone_top), 0, 1e6, "ozone tent profile: zero above this altitude, m").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(real("ground_albedo", CV_AT(ground_albedo), 0, 1, "ground albedo of the planet beyond the ground mesh (seen through the air)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(real("sun_angular_radius", CV_AT(sun_angular_radius_deg), 0.01, 10, "sun angular radius, degrees (the disc, and the smooth set of the sunlight below the horizon)").in(cloudgen::ParamGroup::LightAndSky));
  t.push_back(integer("scattering_orders", CV_AT(scattering_orders), 1, 64,
                      "scattering orders of the sky: 1 = single scattering; N adds orders 2..N from the "
                      "multiple-scattering LUT (Hillaire 2020; large N tends to its infinite series L2 / (1 - f))").in(cloudgen::ParamGroup::LightAndSky, true));
  t.push_back(boolean("density_orders", CV_AT(density_orders),
                      "with render.sky_lut=true: the orders 2..N by Bruneton's scattering-density passes (each order's "
                      "light from the last one's, with the true phase functions, in an 8x32x32x16 table; seconds of "
                      "precompute) instead of the Psi_ms series; the per-pixel march always uses Psi_ms").in(cloudgen::ParamGroup::LightAndSky, true));
  return t;
}

}  // namespace

bool AtmosphereSettings::operator==(const AtmosphereSettings& o) const {
  return bottom_radius == o.bottom_radius && top_radius == o.top_radius && rayleigh == o.rayleigh &&
         rayleigh_scattering == o.rayleigh_scattering && rayleigh_height == o.rayleigh_height && mie == o.mie &&
         mie_extinction == o.mie_extinction && mie_scattering == o.mie_scattering && mie_height == o.mie_height &&
         mie_g == o.mie_g && ozone == o.ozone && ozone_absorption == o.ozone_absorption &&
         ozone_bottom == o.ozone_bottom && ozone_peak == o.ozone_peak && ozone_top == o.ozone_top &&
         ground_albedo == o.ground_albedo && sun_angular_radius_deg == o.sun_angular_radius_deg &&
         scattering_orders == o.scattering_orders && density_orders == o.density_orders;
}

const std::vector<AtmosphereParamDef>& atmosphere_params() {
  static const std::vector<AtmosphereParamDef> table = build();
  return table;
}

void apply_atmosphere_setting(AtmosphereSettings& s, const std::string& assignment) {
  auto eq = assignment.find('=');
  if (eq == std::string::npos) throw InputError("--set " + assignment + ": expected atmosphere.key=value");
  std::string key = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  if (key.rfind("atmosphere.", 0) == 0) key = key.substr(11);
  std::string known;
  for (const AtmosphereParamDef& p : atmosphere_params()) {
    if (p.key == key) {
      p.set(s, value);
      return;
    }
    known += (known.empty() ? "" : ", ") + p.key;
  }
  throw InputError("--set " + assignment + ": unknown key atmosphere." + key + " (known: " + known + ")");
}

void validate_atmosphere(const AtmosphereSettings& s) {
  if (!(s.top_radius > s.bottom_radius))
    throw InputError("atmosphere.top_radius=" + fmt(s.top_radius) + " must exceed atmosphere.bottom_radius=" +
                     fmt(s.bottom_radius));
  if (!(s.ozone_bottom < s.ozone_peak && s.ozone_peak < s.ozone_top))
    throw InputError("atmosphere.ozone_bottom=" + fmt(s.ozone_bottom) + ", ozone_peak=" + fmt(s.ozone_peak) +
                     ", ozone_top=" + fmt(s.ozone_top) + ": need bottom < peak < top");
  if (s.mie_scattering > s.mie_extinction)
    throw InputError("atmosphere.mie_scattering=" + fmt(s.mie_scattering) + " exceeds atmosphere.mie_extinction=" +
                     fmt(s.mie_extinction) + " (scattering is part of extinction)");
}

std::string atmosphere_params_markdown() { return param::grouped_markdown(atmosphere_params(), "atmosphere.", "###"); }

std::string atmosphere_params_help() {
  std::string s = "atmosphere parameters (--set atmosphere.KEY=VALUE):\n";
  AtmosphereSettings d;
  for (const AtmosphereParamDef& p : atmosphere_params())
    s += cloudgen::help_entry(p.key + " (" + p.type + ", " + p.range + ", default " + p.get(d) + ")", p.doc);
  return s;
}

}  // namespace cloudviewer
