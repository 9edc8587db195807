// Phase functions of cloud droplets: a Lorenz-Mie solver (Bohren & Huffman 1983, "Absorption and
// Scattering of Light by Small Particles", appendix A: BHMIE, with the logarithmic derivative by
// downward recurrence) integrated over a modified-gamma droplet size distribution (Hansen & Travis
// 1974), and the analytic approximations renderers use: Henyey-Greenstein, a two-lobe HG, and
// Jendersie & d'Eon's HG + Draine fit (SIGGRAPH 2023, "An Approximate Mie Scattering Function for
// Fog and Cloud Rendering"). All in double precision; phase values are per steradian and
// integrate to 1 over the sphere.
#pragma once

#include <array>
#include <complex>
#include <string>
#include <vector>

namespace cloudgen::phase {

/// Efficiencies and the angular amplitudes of one sphere.
struct MieSphere {
  double qext = 0, qsca = 0, qback = 0;  ///< extinction, scattering, backscatter efficiency
  double g = 0;                          ///< asymmetry parameter <cos theta>
  /// 0.5 (|S1|^2 + |S2|^2) at each requested cos(theta): unpolarised scattered intensity.
  std::vector<double> intensity;
};

/// One homogeneous sphere of size parameter x = 2 pi r / lambda and relative refractive index m
/// (imaginary part >= 0 absorbs), evaluated at the cosines `mu`. Throws InputError for x <= 0 or
/// x > 20000 (beyond that the series needs more terms than double precision keeps stable).
MieSphere mie_sphere(double x, std::complex<double> m, const std::vector<double>& mu);

/// Modified gamma size distribution n(r) ~ r^((1 - 3 v) / v) exp(-r / (r_eff v)) (Hansen & Travis):
/// effective radius r_eff (um) and effective variance v. Cloud default: 10 um, 0.111.
struct DropletSizes {
  double effective_radius_um = 10;
  double effective_variance = 0.111;
  int radii = 0;  ///< quadrature nodes over r; 0 = chosen from the size parameter
};

/// Bulk optical properties of the droplet population at one wavelength.
struct BulkPhase {
  double wavelength_nm = 550;
  double g = 0;                 ///< asymmetry parameter of the population
  double qext_effective = 0;    ///< <C_ext> / <pi r^2>: tends to 2 for large droplets
  std::vector<double> angle_deg, value;  ///< the phase function per steradian, normalised to 1
};

/// The population's phase function at `angles_deg` (ascending, 0..180), water index 1.333 + 0i
/// (1.331 at 650 nm, 1.333 at 550, 1.337 at 450: Hale & Querry 1973).
BulkPhase mie_population(const DropletSizes& sizes, double wavelength_nm, const std::vector<double>& angles_deg);

/// Refractive index of water at a visible wavelength (Hale & Querry 1973, linear in between).
double water_index(double wavelength_nm);

double henyey_greenstein(double g, double cos_theta);
/// w HG(g1) + (1 - w) HG(g2) (g2 < 0: the backward lobe).
double two_lobe_hg(double g1, double g2, double w, double cos_theta);
/// Draine's phase function (Draine 2003): HG times (1 + alpha cos^2) / (1 + alpha (1 + 2 g^2) / 3).
double draine(double g, double alpha, double cos_theta);
/// Draine's lobe's cumulative distribution over the scattering cosine: the probability that
/// cos theta <= c (0 at c = -1, 1 at c = 1). Closed form for |g| >= 0.05; below, where the closed
/// form's 1/g^3 terms cancel, Gauss-Legendre quadrature (the integrand is then nearly a cubic).
double draine_cdf(double g, double alpha, double c);
/// The scattering cosine at which draine_cdf reaches u in [0, 1]: an exact inverse-CDF sample of
/// Draine's lobe (Newton's method on draine_cdf, kept inside a shrinking bracket; the result is
/// within 1e-12 of the root), so a path tracer weights it by 1 instead of phase / pdf.
double sample_draine(double g, double alpha, double u);
/// Jendersie & d'Eon 2023: (1 - w_D) HG(g_HG) + w_D Draine(g_D, alpha), parameters fitted as
/// functions of the droplet diameter d in [5, 50] um.
struct DraineHgFit {
  double g_hg, g_d, alpha, w_d;
};
DraineHgFit draine_hg_fit(double diameter_um);
double draine_hg(const DraineHgFit& f, double cos_theta);

/// Angles for a phase table: 0.01 degree steps to 5 degrees (the forward peak), then 0.1 degree
/// steps to 180: 2251 angles.
std::vector<double> table_angles();

/// 2 pi * integral of p(theta) sin(theta) dtheta (trapezoid on the given grid): 1 for a phase function.
double sphere_integral(const std::vector<double>& angle_deg, const std::vector<double>& value);
/// 2 pi * integral of p cos(theta) sin(theta) dtheta: the asymmetry parameter.
double asymmetry(const std::vector<double>& angle_deg, const std::vector<double>& value);

}  // namespace cloudgen::phase
