// Lorenz-Mie scattering by water droplets and the analytic phase functions (see cloudgen/phase.h).
#include "cloudgen/phase.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "cloudgen/glsl_prelude.h"
#include "cloudgen/volume.h"

namespace cloudgen::phase {

namespace {
using cd = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;
}  // namespace

MieSphere mie_sphere(double x, cd m, const std::vector<double>& mu) {
  if (!(x > 0) || x > 20000) throw InputError("Mie size parameter " + std::to_string(x) + " is outside (0, 20000]");
  if (!(m.real() > 0) || m.imag() < 0) throw InputError("Mie refractive index needs a positive real part and k >= 0");
  MieSphere out;
  const cd y = m * x;
  // Bohren & Huffman: series length Wiscombe's x + 4 x^(1/3) + 2; the logarithmic derivative
  // D_n(mx) by downward recurrence from well above both x and |mx|, where it is stable.
  const int nstop = int(x + 4 * std::cbrt(x) + 2);
  const int nmx = int(std::max(double(nstop), std::abs(y))) + 15;
  std::vector<cd> D(size_t(nmx) + 1, cd(0, 0));
  for (int n = nmx; n >= 2; --n) D[size_t(n - 1)] = double(n) / y - 1.0 / (D[size_t(n)] + double(n) / y);
  const size_t na = mu.size();
  std::vector<double> pi0(na, 0.0), pi1(na, 1.0);
  std::vector<cd> s1(na, 0.0), s2(na, 0.0);
  double psi0 = std::cos(x), psi1 = std::sin(x), chi0 = -std::sin(x), chi1 = std::cos(x);
  cd xi1(psi1, -chi1), an1(0, 0), bn1(0, 0);
  double qsca = 0, qext = 0, gq = 0;
  cd back(0, 0);
  for (int n = 1; n <= nstop; ++n) {
    const double fn = (2.0 * n + 1) / (double(n) * (n + 1));
    const double psi = (2.0 * n - 1) * psi1 / x - psi0;
    const double chi = (2.0 * n - 1) * chi1 / x - chi0;
    const cd xi(psi, -chi);
    const cd da = D[size_t(n)] / m + double(n) / x;
    const cd db = D[size_t(n)] * m + double(n) / x;
    const cd an = (da * psi - psi1) / (da * xi - xi1);
    const cd bn = (db * psi - psi1) / (db * xi - xi1);
    qsca += (2.0 * n + 1) * (std::norm(an) + std::norm(bn));
    qext += (2.0 * n + 1) * (an + bn).real();
    gq += fn * (an * std::conj(bn)).real();
    if (n > 1) gq += (double(n - 1) * (n + 1) / n) * (an1 * std::conj(an) + bn1 * std::conj(bn)).real();
    back += (2.0 * n + 1) * ((n % 2) ? -1.0 : 1.0) * (an - bn);
    for (size_t j = 0; j < na; ++j) {
      const double p = pi1[j], pm = pi0[j];
      const double t = n * mu[j] * p - (n + 1) * pm;  // tau_n
      s1[j] += fn * (an * p + bn * t);
      s2[j] += fn * (an * t + bn * p);
      pi0[j] = p;
      pi1[j] = ((2.0 * n + 1) * mu[j] * p - (n + 1) * pm) / n;  // pi_{n+1}
    }
    psi0 = psi1, psi1 = psi, chi0 = chi1, chi1 = chi;
    xi1 = cd(psi1, -chi1);
    an1 = an, bn1 = bn;
  }
  out.qsca = 2.0 / (x * x) * qsca;
  out.qext = 2.0 / (x * x) * qext;
  out.qback = std::norm(back) / (x * x);
  out.g = 2.0 * gq / qsca;
  out.intensity.resize(na);
  for (size_t j = 0; j < na; ++j) out.intensity[j] = 0.5 * (std::norm(s1[j]) + std::norm(s2[j]));
  return out;
}

double water_index(double wavelength_nm) {
  // Hale & Querry 1973 (real part; the imaginary part is below 1e-8 in the visible).
  const double l[] = {400, 450, 500, 550, 600, 650, 700}, n[] = {1.339, 1.337, 1.335, 1.333, 1.332, 1.331, 1.331};
  if (wavelength_nm <= l[0]) return n[0];
  for (int i = 0; i < 6; ++i)
    if (wavelength_nm <= l[i + 1]) return n[i] + (n[i + 1] - n[i]) * (wavelength_nm - l[i]) / (l[i + 1] - l[i]);
  return n[6];
}

std::vector<double> table_angles() {
  std::vector<double> a;
  for (int i = 0; i < 500; ++i) a.push_back(i * 0.01);
  for (int i = 50; i <= 1800; ++i) a.push_back(i * 0.1);
  return a;
}

double sphere_integral(const std::vector<double>& angle_deg, const std::vector<double>& value) {
  double s = 0;
  for (size_t i = 0; i + 1 < angle_deg.size(); ++i) {
    const double t0 = angle_deg[i] * kPi / 180, t1 = angle_deg[i + 1] * kPi / 180;
    s += 0.5 * (value[i] * std::sin(t0) + value[i + 1] * std::sin(t1)) * (t1 - t0);
  }
  return 2 * kPi * s;
}

double asymmetry(const std::vector<double>& angle_deg, const std::vector<double>& value) {
  std::vector<double> w(value.size());
  for (size_t i = 0; i < value.size(); ++i) w[i] = value[i] * std::cos(angle_deg[i] * kPi / 180);
  return sphere_integral(angle_deg, w);
}

BulkPhase mie_population(const DropletSizes& sz, double wavelength_nm, const std::vector<double>& angles_deg) {
  if (!(sz.effective_radius_um >= 0.5 && sz.effective_radius_um <= 100))
    throw InputError("effective radius " + std::to_string(sz.effective_radius_um) + " um is outside [0.5, 100]");
  if (!(sz.effective_variance >= 0.01 && sz.effective_variance <= 0.3))
    throw InputError("effective variance " + std::to_string(sz.effective_variance) + " is outside [0.01, 0.3]");
  if (!(wavelength_nm >= 300 && wavelength_nm <= 1000))
    throw InputError("wavelength " + std::to_string(wavelength_nm) + " nm is outside [300, 1000]");
  const double a = sz.effective_radius_um, v = sz.effective_variance;
  const double shape = (1 - 3 * v) / v, scale = a * v;  // n(r) ~ r^shape exp(-r / scale)
  // Nodes from 0 to where n(r) r^2 (the scattering weight) is below 1e-9 of its peak.
  const double peak = (shape + 2) * scale;
  auto logw = [&](double r) { return (shape + 2) * std::log(r) - r / scale; };
  double r_hi = peak;
  while (logw(r_hi) - logw(peak) > std::log(1e-9)) r_hi *= 1.05;
  const double lambda_um = wavelength_nm * 1e-3;
  const int radii = sz.radii > 0 ? sz.radii
                                 : std::clamp(int(2 * kPi * r_hi / lambda_um / 0.5), 200, 4000);  // dx ~ 0.5
  const double dr = r_hi / radii;
  std::vector<double> mu(angles_deg.size());
  for (size_t j = 0; j < mu.size(); ++j) mu[j] = std::cos(angles_deg[j] * kPi / 180);
  const cd m(water_index(wavelength_nm), 0.0);
  std::vector<MieSphere> spheres(static_cast<size_t>(radii));
  tbb::parallel_for(0, radii, [&](int i) {
    const double r = (i + 0.5) * dr;
    spheres[size_t(i)] = mie_sphere(2 * kPi * r / lambda_um, m, mu);
  });
  // Sums in a fixed order: the same bytes at any thread count.
  BulkPhase out;
  out.wavelength_nm = wavelength_nm;
  out.angle_deg = angles_deg;
  out.value.assign(angles_deg.size(), 0.0);
  double csca = 0, cext = 0, area = 0, gsum = 0;
  for (int i = 0; i < radii; ++i) {
    const double r = (i + 0.5) * dr;
    const double n = std::exp(shape * std::log(r / peak) - (r - peak) / scale);  // scaled to avoid overflow
    const MieSphere& s = spheres[size_t(i)];
    const double geo = kPi * r * r;
    area += n * geo;
    cext += n * s.qext * geo;
    csca += n * s.qsca * geo;
    gsum += n * s.qsca * geo * s.g;
    for (size_t j = 0; j < mu.size(); ++j) out.value[j] += n * s.intensity[j];  // dC/dOmega * k^2
  }
  out.g = gsum / csca;
  out.qext_effective = cext / area;
  const double norm = sphere_integral(out.angle_deg, out.value);
  for (double& p : out.value) p /= norm;
  return out;
}

namespace lobes {
CV_GLSL_DOUBLE_TYPES;
CV_GLSL_BUILTINS;
#include "cloudgen/phase_lobes.glsl"
}  // namespace lobes

double henyey_greenstein(double g, double c) { return lobes::lobe_hg(g, c); }

double two_lobe_hg(double g1, double g2, double w, double c) { return lobes::lobe_two_hg(g1, g2, w, c); }

double draine(double g, double alpha, double c) { return lobes::lobe_draine(g, alpha, c); }

// With s = 1 + g^2 - 2 g x, the integral of (1 + alpha x^2) s^(-3/2) over x in [-1, c] is
// (J(s(-1)) - J(s(c))) / (2 g) with J(s) = -2 (1 + alpha a^2 / b^2) s^(-1/2) - 4 alpha a / b^2 s^(1/2)
// + 2 alpha / (3 b^2) s^(3/2), a = 1 + g^2, b = 2 g; Draine's normalisation 2 pi K, K = (1 - g^2) /
// (4 pi (1 + alpha (1 + 2 g^2) / 3)), turns it into the probability.
double draine_cdf(double g, double alpha, double c) {
  c = std::clamp(c, -1.0, 1.0);
  if (std::fabs(g) < 0.05) {
    // 8-point Gauss-Legendre on 4 panels of [-1, c]: the integrand's nearest singularity is at
    // x = (1 + g^2) / (2 g), beyond 10, so the rule is exact to rounding.
    static const double node[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double weight[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const double h = (c + 1) / 4;
    double sum = 0;
    for (int panel = 0; panel < 4; ++panel) {
      const double mid = -1 + h * (panel + 0.5);
      for (int k = 0; k < 4; ++k)
        for (double sign : {-1.0, 1.0}) sum += weight[k] * draine(g, alpha, mid + sign * node[k] * h / 2);
    }
    return std::clamp(2 * M_PI * sum * h / 2, 0.0, 1.0);
  }
  const double a = 1 + g * g, b = 2 * g;
  auto J = [&](double s) {
    const double r = std::sqrt(s);
    return -2 * (1 + alpha * a * a / (b * b)) / r - 4 * alpha * a / (b * b) * r + 2 * alpha / (3 * b * b) * s * r;
  };
  const double norm = (1 - g * g) / (2 * (1 + alpha * (1 + 2 * g * g) / 3));
  return std::clamp(norm * (J((1 + g) * (1 + g)) - J(a - b * c)) / b, 0.0, 1.0);
}

double sample_draine(double g, double alpha, double u) {
  u = std::clamp(u, 0.0, 1.0);
  double lo = -1, hi = 1;
  // Start from HG's inverse CDF at the same u: Draine is HG times a smooth factor.
  double c = 1 - 2 * u;
  if (std::fabs(g) > 1e-4) {
    const double q = (1 - g * g) / (1 - g + 2 * g * u);
    c = std::clamp((1 + g * g - q * q) / (2 * g), -1.0, 1.0);
  }
  for (int it = 0; it < 100; ++it) {
    const double f = draine_cdf(g, alpha, c) - u;
    if (f == 0) return c;
    (f < 0 ? lo : hi) = c;
    const double step = f / (2 * M_PI * draine(g, alpha, c));
    double next = c - step;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // Newton left the bracket: bisect
    if (std::fabs(next - c) < 1e-14 || hi - lo < 1e-14) return next;
    c = next;
  }
  return c;
}

DraineHgFit draine_hg_fit(double d) {
  if (!(d >= 5 && d <= 50)) throw InputError("HG+Draine fit: droplet diameter " + std::to_string(d) + " um is outside [5, 50]");
  return {lobes::draine_fit_g_hg(d), lobes::draine_fit_g_d(d), lobes::draine_fit_alpha(d), lobes::draine_fit_w_d(d)};
}

double draine_hg(const DraineHgFit& f, double c) { return lobes::lobe_draine_hg(f.g_hg, f.g_d, f.alpha, f.w_d, c); }

}  // namespace cloudgen::phase
