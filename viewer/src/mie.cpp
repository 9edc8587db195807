// The Mie phase table of cloud droplets, from cloudgen's Lorenz-Mie solver (cloudgen/phase.h: BHMIE
// over the default modified-gamma droplet population, 550 nm; the same numbers `cloudgen phase`
// writes), and the parser of --mie-table files that replace it. phase.glsl interpolates the table
// in log space (the forward peak is ~3e5 times the side value), so both are normalised under that
// interpolant.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>

#include "cloudgen/phase.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

namespace {
std::mutex g_mie_mutex;
std::vector<float> g_mie_override;

// 2 pi int p(theta) sin(theta) dtheta of the table over equal steps in theta = 0..pi, p between two
// entries interpolated in log space as phase.glsl does (16 midpoints per step).
double log_table_integral(const std::vector<double>& t) {
  const size_t n = t.size();
  double sum = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    const double t0 = M_PI * double(i) / double(n - 1), dt = M_PI / double(n - 1);
    const double la = std::log(std::max(t[i], 1e-30)), lb = std::log(std::max(t[i + 1], 1e-30));
    for (int k = 0; k < 16; ++k) {
      const double f = (k + 0.5) / 16;
      sum += std::exp(la + (lb - la) * f) * std::sin(t0 + f * dt) * (dt / 16);
    }
  }
  return 2 * M_PI * sum;
}
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
  if (!(*std::max_element(t.begin(), t.end()) > 0))
    throw InputError("--mie-table " + path + ": the phase function integrates to 0");
  const double integral = log_table_integral(t);
  g_mie_override.resize(n);
  for (int i = 0; i < n; ++i) g_mie_override[size_t(i)] = float(t[size_t(i)] / integral);
}

const std::vector<float>& mie_phase_table(int n) {
  static std::vector<float> table;
  static int cached_n = 0;
  std::lock_guard<std::mutex> lock(g_mie_mutex);
  if (!g_mie_override.empty()) return g_mie_override;
  if (cached_n == n) return table;
  // cloudgen's Mie solver over its default droplet population (effective radius 10 um, variance
  // 0.111), green (550 nm), at the table's own angles.
  std::vector<double> angles(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) angles[size_t(j)] = 180.0 * j / (n - 1);
  std::vector<double> acc = cloudgen::phase::mie_population(cloudgen::phase::DropletSizes{}, 550.0, angles).value;
  const double integral = log_table_integral(acc);
  table.resize(size_t(n));
  for (int j = 0; j < n; ++j) table[size_t(j)] = float(acc[size_t(j)] / integral);
  cached_n = n;
  return table;
}

}  // namespace cloudviewer
