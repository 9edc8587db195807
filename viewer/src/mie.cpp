// The Mie phase table of cloud droplets (Lorenz-Mie series, Bohren & Huffman's BHMIE) and the
// parser of --mie-table files that replace it.
#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <mutex>
#include <sstream>

#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

namespace {
std::mutex g_mie_mutex;
std::vector<float> g_mie_override;
}  // namespace

void load_mie_table(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mie_mutex);
  if (path.empty()) {
    g_mie_override.clear();
    return;
  }
  std::ifstream in(path);
  if (!in) throw InputError("--mie-table " + path + ": no such file");
  std::vector<double> theta, value;
  std::string line;
  int columns = 0, line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::vector<double> nums;
    double d;
    while (ls >> d) nums.push_back(d);
    if (!ls.eof()) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": not a number");
    if (nums.empty()) continue;
    if (columns == 0) columns = int(nums.size());
    if (int(nums.size()) != columns || columns > 2)
      throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": expected " +
                       (columns == 2 ? "2 columns (theta_degrees value)" : "1 value per line"));
    for (double x : nums)
      if (!std::isfinite(x)) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": not finite");
    if (columns == 2) theta.push_back(nums[0]), value.push_back(nums[1]);
    else value.push_back(nums[0]);
    if (value.back() < 0) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": negative phase value");
  }
  if (value.size() < 2) throw InputError("--mie-table " + path + ": needs at least 2 values");
  if (columns == 1)
    for (size_t i = 0; i < value.size(); ++i) theta.push_back(180.0 * double(i) / double(value.size() - 1));
  for (size_t i = 1; i < theta.size(); ++i)
    if (!(theta[i] > theta[i - 1])) throw InputError("--mie-table " + path + ": theta must increase");
  if (theta.front() > 1e-6 || theta.back() < 180 - 1e-6)
    throw InputError("--mie-table " + path + ": theta must cover 0 to 180 degrees");
  const int n = 1801;
  std::vector<double> t(n);
  size_t j = 0;
  for (int i = 0; i < n; ++i) {
    double th = 180.0 * i / (n - 1);
    while (j + 2 < theta.size() && theta[j + 1] < th) ++j;
    double f = std::clamp((th - theta[j]) / (theta[j + 1] - theta[j]), 0.0, 1.0);
    t[size_t(i)] = value[j] + f * (value[j + 1] - value[j]);
  }
  double integral = 0;
  for (int i = 0; i + 1 < n; ++i) {
    double t0 = M_PI * i / (n - 1), t1 = M_PI * (i + 1) / (n - 1);
    integral += 0.5 * (t[size_t(i)] * std::sin(t0) + t[size_t(i + 1)] * std::sin(t1)) * (t1 - t0);
  }
  integral *= 2 * M_PI;
  if (!(integral > 0)) throw InputError("--mie-table " + path + ": the phase function integrates to 0");
  g_mie_override.resize(n);
  for (int i = 0; i < n; ++i) g_mie_override[size_t(i)] = float(t[size_t(i)] / integral);
}

const std::vector<float>& mie_phase_table(int n) {
  static std::vector<float> table;
  static int cached_n = 0;
  std::lock_guard<std::mutex> lock(g_mie_mutex);
  if (!g_mie_override.empty()) return g_mie_override;
  if (cached_n == n) return table;
  // Lorenz-Mie series (Bohren & Huffman's BHMIE) for water droplets, averaged over Deirmendjian's
  // C.1 cloud size distribution n(r) ~ r^6 exp(-1.5 r), r in micrometres (mode 4 um), weighted by
  // each droplet's scattering (|S1|^2 + |S2|^2 sums already carry the cross-section).
  using cd = std::complex<double>;
  const double lambda_um = 0.55;
  const cd m(1.333, 0.0);
  std::vector<double> mu(size_t(n), 0.0), acc(size_t(n), 0.0);
  for (int j = 0; j < n; ++j) mu[size_t(j)] = std::cos(M_PI * j / (n - 1));
  const int radii = 48;
  const double r_min = 0.5, r_max = 16.0;
  for (int ri = 0; ri < radii; ++ri) {
    double r = r_min + (r_max - r_min) * (ri + 0.5) / radii;
    double weight = std::pow(r, 6) * std::exp(-1.5 * r);
    double x = 2 * M_PI * r / lambda_um;
    cd y = m * x;
    int nstop = int(x + 4 * std::cbrt(x) + 2);
    int nmx = int(std::max(double(nstop), std::abs(y))) + 16;
    std::vector<cd> D(size_t(nmx) + 1, cd(0, 0));
    for (int k = nmx; k >= 2; --k) D[size_t(k - 1)] = double(k) / y - 1.0 / (D[size_t(k)] + double(k) / y);
    double psi0 = std::cos(x), psi1 = std::sin(x), chi0 = -std::sin(x), chi1 = std::cos(x);
    cd xi1(psi1, -chi1);
    std::vector<double> pi0(size_t(n), 0.0), pi1(size_t(n), 1.0);
    std::vector<cd> s1(size_t(n), 0.0), s2(size_t(n), 0.0);
    for (int k = 1; k <= nstop; ++k) {
      double fn = (2.0 * k + 1) / (double(k) * (k + 1));
      double psi = (2.0 * k - 1) * psi1 / x - psi0;
      double chi = (2.0 * k - 1) * chi1 / x - chi0;
      cd xi(psi, -chi);
      cd da = D[size_t(k)] / m + double(k) / x;
      cd db = D[size_t(k)] * m + double(k) / x;
      cd an = (da * psi - psi1) / (da * xi - xi1);
      cd bn = (db * psi - psi1) / (db * xi - xi1);
      for (int j = 0; j < n; ++j) {
        double p = pi1[size_t(j)];
        double t = k * mu[size_t(j)] * p - (k + 1) * pi0[size_t(j)];
        s1[size_t(j)] += fn * (an * p + bn * t);
        s2[size_t(j)] += fn * (an * t + bn * p);
        double pn = ((2.0 * k + 1) * mu[size_t(j)] * p - (k + 1) * pi0[size_t(j)]) / k;
        pi0[size_t(j)] = p;
        pi1[size_t(j)] = pn;
      }
      psi0 = psi1, psi1 = psi, chi0 = chi1, chi1 = chi;
      xi1 = cd(psi1, -chi1);
    }
    for (int j = 0; j < n; ++j) acc[size_t(j)] += weight * 0.5 * (std::norm(s1[size_t(j)]) + std::norm(s2[size_t(j)]));
  }
  // Normalise: 2 pi * integral p(theta) sin(theta) dtheta = 1 (trapezoid on the table's own grid,
  // the same piecewise-linear function the renderers interpolate).
  double integral = 0;
  for (int j = 0; j + 1 < n; ++j) {
    double t0 = M_PI * j / (n - 1), t1 = M_PI * (j + 1) / (n - 1);
    integral += 0.5 * (acc[size_t(j)] * std::sin(t0) + acc[size_t(j + 1)] * std::sin(t1)) * (t1 - t0);
  }
  integral *= 2 * M_PI;
  table.resize(size_t(n));
  for (int j = 0; j < n; ++j) table[size_t(j)] = float(acc[size_t(j)] / integral);
  cached_n = n;
  return table;
}

}  // namespace cloudviewer
