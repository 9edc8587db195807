// The Mie phase table of cloud droplets, from cloudgen's Lorenz-Mie solver (cloudgen/phase.h: BHMIE
// over the default modified-gamma droplet population at 650, 550 and 450 nm; the same numbers
// `cloudgen phase` writes), and the parser of --mie-table files that replace it. phase.glsl interpolates the table
// in log space (the forward peak is ~3e5 times the side value), so both are normalised under that
// interpolant.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "cloudgen/phase.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"
#include "cloudgen/input_scope.h"

namespace cloudviewer {

namespace {
std::atomic<uint64_t> g_next_mie_id{1};
const double kWavelengthsNm[3] = {650.0, 550.0, 450.0};

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

// Three channels of CV_MIE_TABLE_SIZE values, each normalised under the log interpolant.
MiePhaseTable normalised(const std::vector<double> (&channels)[3], const std::string& what) {
  MiePhaseTable t;
  const int n = int(channels[0].size());
  t.rgb.resize(size_t(n) * 3);
  const char* names[3] = {"red", "green", "blue"};
  for (int c = 0; c < 3; ++c) {
    // All zero: the log interpolant's floor (1e-30) would integrate to a tiny positive number.
    if (!(*std::max_element(channels[c].begin(), channels[c].end()) > 0))
      throw InputError(what + ": the " + names[c] + " channel's phase function integrates to 0");
    const double integral = log_table_integral(channels[c]);
    if (!(integral > 0) || !std::isfinite(integral)) throw InputError(what + ": the phase function integrates to 0");
    for (int i = 0; i < n; ++i) t.rgb[size_t(i) * 3 + size_t(c)] = float(channels[c][size_t(i)] / integral);
  }
  t.id = g_next_mie_id++;
  return t;
}
}  // namespace

std::shared_ptr<const MiePhaseTable> read_mie_table(const std::string& path) {
  const std::string what = "--mie-table " + path;
  std::istringstream in(cloudgen::read_text_input(path, "the Mie table " + path, what));
  std::vector<double> theta, value[3];
  std::string line;
  int columns = 0, line_no = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++line_no;
    auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::replace(line.begin(), line.end(), ',', ' ');  // cloudgen phase's CSV
    std::istringstream ls(line);
    std::vector<double> nums;
    double d;
    while (ls >> d) nums.push_back(d);
    const std::string where = what + ":" + std::to_string(line_no);
    if (!ls.eof()) {
      if (header_allowed && nums.empty()) {  // a header line such as "angle_deg,r,g,b"
        header_allowed = false;
        continue;
      }
      throw InputError(where + ": not a number");
    }
    if (nums.empty()) continue;
    header_allowed = false;
    if (columns == 0) columns = int(nums.size());
    if (int(nums.size()) != columns || columns == 3 || columns > 4)
      throw InputError(where + ": expected " +
                       std::string(columns == 4 ? "4 columns (angle_deg,r,g,b)"
                                   : columns == 2 ? "2 columns (theta_degrees value)"
                                   : columns == 1 ? "1 value per line"
                                                  : "1 value, 2 columns (theta value) or 4 (angle_deg,r,g,b)"));
    for (double x : nums)
      if (!std::isfinite(x)) throw InputError(where + ": not finite");
    if (columns >= 2) theta.push_back(nums[0]);
    for (int c = 0; c < 3; ++c) {
      const double v = columns == 4 ? nums[size_t(c) + 1] : nums.back();
      if (v < 0) throw InputError(where + ": negative phase value");
      value[c].push_back(v);
    }
  }
  if (value[0].size() < 2) throw InputError(what + ": needs at least 2 values");
  if (columns == 1)
    for (size_t i = 0; i < value[0].size(); ++i) theta.push_back(180.0 * double(i) / double(value[0].size() - 1));
  for (size_t i = 1; i < theta.size(); ++i)
    if (!(theta[i] > theta[i - 1])) throw InputError(what + ": theta must increase");
  if (theta.front() > 1e-6 || theta.back() < 180 - 1e-6) throw InputError(what + ": theta must cover 0 to 180 degrees");
  const int n = CV_MIE_TABLE_SIZE;
  std::vector<double> t[3];
  for (int c = 0; c < 3; ++c) {
    t[c].resize(size_t(n));
    size_t j = 0;
    for (int i = 0; i < n; ++i) {
      double th = 180.0 * i / (n - 1);
      while (j + 2 < theta.size() && theta[j + 1] < th) ++j;
      double f = std::clamp((th - theta[j]) / (theta[j + 1] - theta[j]), 0.0, 1.0);
      t[c][size_t(i)] = value[c][j] + f * (value[c][j + 1] - value[c][j]);
    }
  }
  return std::make_shared<const MiePhaseTable>(normalised(t, what));
}

std::shared_ptr<const MiePhaseTable> mie_table_of(const RenderSettings& s) {
  return s.mie_table ? s.mie_table : computed_mie_table();
}

std::shared_ptr<const MiePhaseTable> computed_mie_table() {
  static std::mutex mutex;
  static std::shared_ptr<const MiePhaseTable> table;
  std::lock_guard<std::mutex> lock(mutex);
  if (table) return table;
  // cloudgen's Mie solver over its default droplet population (effective radius 10 um, variance
  // 0.111) at the table's own angles, per channel.
  const int n = CV_MIE_TABLE_SIZE;
  std::vector<double> angles(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) angles[size_t(j)] = 180.0 * j / (n - 1);
  std::vector<double> acc[3];
  for (int c = 0; c < 3; ++c)
    acc[c] = cloudgen::phase::mie_population(cloudgen::phase::DropletSizes{}, kWavelengthsNm[c], angles).value;
  table = std::make_shared<const MiePhaseTable>(normalised(acc, "the computed Mie table"));
  return table;
}

}  // namespace cloudviewer
