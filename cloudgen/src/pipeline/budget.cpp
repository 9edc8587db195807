#include "cloudgen/budget.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cloudgen/errors.h"
#include "cloudgen/generate.h"
#include "cloudgen/printable.h"

namespace cloudgen {

uint64_t parse_voxel_count(const std::string& text, const std::string& flag, uint64_t min) {
  const std::string form = "; allowed: a voxel count like 200M, 1.5G, 64K or 5000000 (K = 1e3, M = 1e6, G = 1e9), at least " +
                           std::to_string(min);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  const std::string suf = end ? std::string(end) : std::string();
  const double m = suf.empty() ? 1 : suf == "K" || suf == "k" ? 1e3 : suf == "M" ? 1e6 : suf == "G" ? 1e9 : -1;
  if (text.empty() || end == text.c_str() || m < 0 || !std::isfinite(v) || v * m < double(min) || v * m > 1e18)
    throw InputError(flag + ": \"" + printable(text) + "\"" + form);
  return uint64_t(std::llround(v * m));
}

namespace {

uint64_t voxels(const std::array<uint32_t, 3>& r) { return uint64_t(r[0]) * r[1] * r[2]; }

Preset rescaled(const Preset& p, uint32_t n) {
  Preset q = p;
  rescale(q, n);
  return q;
}

}  // namespace

BudgetChoice choose_for_budget(const Preset& p, uint64_t budget, int threads) {
  BudgetChoice c;
  c.budget = budget;
  const uint32_t longest = *std::max_element(p.resolution.begin(), p.resolution.end());
  // The sample: the largest rescale of at most 2 M voxels (the preset's own if smaller).
  constexpr uint64_t kSampleVoxels = uint64_t(1) << 21;
  uint32_t lo = 1, hi = std::min<uint32_t>(longest, kMaxResolution);
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo + 1) / 2;
    if (voxels(rescaled(p, mid).resolution) <= kSampleVoxels) lo = mid;
    else hi = mid - 1;
  }
  const Preset sample = rescaled(p, lo);
  GenerateOptions go;
  go.threads = threads;
  go.detail = false;
  go.occupancy = false;
  GenerateStats st;
  generate(sample, go, &st);
  c.sample = sample.resolution;
  c.fraction = double(st.active_voxels) / double(std::max<uint64_t>(1, voxels(sample.resolution)));
  if (st.active_voxels == 0)
    throw InputError("--voxel-budget: the preset holds no cloud at " + std::to_string(c.sample[0]) + "x" +
                     std::to_string(c.sample[1]) + "x" + std::to_string(c.sample[2]) +
                     " voxels, so no voxel size follows from a budget; give --resolution N instead");
  // The largest longest-axis count whose estimate fits (voxel counts grow with n), aiming 5% under
  // the budget: the sampled fraction was 0.1-2.7% under the chosen resolution's on the shipped
  // presets (docs/notes/voxel-budget.md).
  constexpr double kAim = 0.95;
  auto estimate = [&](uint32_t n) { return uint64_t(std::ceil(c.fraction * double(voxels(rescaled(p, n).resolution)))); };
  lo = 1, hi = kMaxResolution;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo + 1) / 2;
    if (estimate(mid) <= kAim * double(budget)) lo = mid;
    else hi = mid - 1;
  }
  const Preset chosen = rescaled(p, lo);
  c.longest = lo;
  c.resolution = chosen.resolution;
  c.voxel_size = chosen.voxel_size;
  GenerateOptions plan_opt;
  plan_opt.threads = threads;
  plan_opt.detail = false;
  const BrickPlan plan = plan_bricks(chosen, plan_opt);
  for (const PlannedBrick& b : plan.bricks)
    if (b.density) c.bound += b.count();
  c.estimate = std::min(estimate(lo), c.bound);
  return c;
}

std::string describe(const BudgetChoice& c) {
  char line[512];
  std::snprintf(line, sizeof line,
                "voxel budget %llu: voxel size %.4g m, resolution %ux%ux%u; about %llu active voxels "
                "(%.2f%% active at %ux%ux%u; the skipping bound allows at most %llu)",
                static_cast<unsigned long long>(c.budget), c.voxel_size, c.resolution[0], c.resolution[1],
                c.resolution[2], static_cast<unsigned long long>(c.estimate), 100.0 * c.fraction, c.sample[0],
                c.sample[1], c.sample[2], static_cast<unsigned long long>(c.bound));
  return line;
}

}  // namespace cloudgen
