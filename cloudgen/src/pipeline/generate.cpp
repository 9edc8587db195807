// The cloud pipeline, brick by brick.
//
// Skipping is exact: density = clamp(scale * (R * profile * coverage - t) / (1 - t), 0, 1) with the
// noise R in [0, 1]. Float multiplication is monotone, so fl(fl(R*P)*C) <= fl(P*C) for R <= 1:
// a brick whose max of P*C (no noise needed) is <= t is zero everywhere, and its noise is never
// evaluated. Skipped and unskipped runs therefore give the same bytes (tested).
//
// With shape sources (shape.h) the noise-free factor is their base density s in place of P*C: a
// brick is empty when a lower bound of the signed distance over the ball around its voxel centres
// proves s = 0 (no voxel visited), else when no voxel's s (the value the brick itself computes)
// passes the threshold with R = 1 (tests/test_shape.cpp).
#include "cloudgen/generate.h"

#include "cloudgen/channel.h"
#include "cloudgen/cloud_type.h"
#include "cloudgen/shape.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/view.h"
#include "cloudgen/weather_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

namespace cloudgen {
namespace {

double smoothstep(double a, double b, double x) {
  double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Portable uniform doubles for tower placement (std distributions differ between libraries).
struct SplitMix {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double a, double b) { return a + (b - a) * double(next() >> 11) * (1.0 / 9007199254740992.0); }
};


}  // namespace

double height_profile(const Preset& p, double h) {
  if (p.height_profile == HeightProfile::Exponential) {
    auto hd = [&](double x) { return (1 - std::exp(-p.height_a * x)) * std::exp(-p.height_b * x); };
    if (!p.height_normalize || p.height_b <= 0) return hd(h);
    // Peak of (1 - e^{-a h}) e^{-b h} is at h* = ln(1 + a/b) / a.
    const double hs = std::log(1 + p.height_a / p.height_b) / p.height_a;
    return hd(h) / hd(hs);
  }
  // Horizon-Zero-Dawn-style cloud-type gradients, defined once in cloud_type.glsl (the viewer's
  // layer mode evaluates the same text).
  if (p.height_profile == HeightProfile::Stratus) return cloud_type::stratus_gradient(h);
  if (p.height_profile == HeightProfile::Cumulonimbus) return cloud_type::cumulonimbus_gradient(h);
  return cloud_type::cumulus_gradient(h);
}

double cloud_type_height_gradient(double h, double type) { return cloud_type::cloud_type_gradient(h, type); }

std::vector<Tower> resolve_towers(const Preset& p) {
  std::vector<Tower> t = p.towers;
  SplitMix rng{p.tower_seed};
  for (int i = 0; i < p.tower_count; ++i) {
    Tower w;
    w.sigma = p.tower_sigma;
    const double mx = 3 * w.sigma[0], mz = 3 * w.sigma[2];
    w.center = {rng.uniform(mx, 1 - mx), rng.uniform(0.15, 0.35), rng.uniform(mz, 1 - mz)};
    w.amplitude = p.tower_amplitude * rng.uniform(0.6, 1.0);
    t.push_back(w);
  }
  return t;
}

std::vector<float> coverage_grid(const Preset& p, uint32_t w, uint32_t h, int threads) {
  std::vector<float> coverage;
  const noise3d::FractalParams cp = coverage_params(p);
  noise3d::GridRegion g;
  g.size = {w, 1, h};
  coverage.resize(g.count());
  noise3d::evaluate_grid(cp, g, coverage.data(), {threads});
  for (float& c : coverage) c = float(smoothstep(p.coverage_low, p.coverage_high, noise_to_unit(cp.kind, c)));
  return coverage;
}

std::vector<float> coverage_map(const Preset& p, int threads) {
  if (!p.coverage_enabled) return {};
  return coverage_grid(p, p.resolution[0], p.resolution[2], threads);
}

namespace {

/// The noise-free factors of the density, shared by the plan (bound) and its execution (values):
/// profile by row, coverage by column, towers per voxel; or, when the preset has shape sources,
/// their base density s alone (shape.h).
struct Shape {
  const Preset& p;
  std::array<uint32_t, 3> N;
  std::vector<float> profile;
  std::vector<float> coverage;  // [z][x] over the whole x-z plane (2D, cheap), empty = 1
  std::vector<Tower> towers;
  WeatherColumns columns;  // a painted weather map's columns (empty: the profile by row applies)
  float t, inv, scale;
  const ShapeField field;                 // empty: no shape sources
  std::array<std::vector<double>, 3> pos;  // shape sources: world metres of the voxel centres per axis

  Shape(const Preset& pr, int threads) : p(pr), N(pr.resolution), field(pr.shape, pr.voxel_size, pr.seed) {
    profile.resize(N[1]);
    for (uint32_t y = 0; y < N[1]; ++y) profile[y] = float(height_profile(p, (y + 0.5) / N[1]));
    t = float(p.threshold), inv = float(1.0 / (1.0 - p.threshold)), scale = float(p.density_scale);
    if (!field.empty()) {
      for (int a = 0; a < 3; ++a)
        for (uint32_t i = 0; i < N[a]; ++i) pos[a].push_back(p.origin[a] + (i + 0.5) * p.voxel_size);
      return;  // the sources replace coverage and towers
    }
    if (p.coverage_enabled && p.coverage_image) {  // painted: coverage, type and top per column
      columns = weather_columns(p, N[0], N[2], threads);
      coverage = columns.coverage;
    } else {
      coverage = coverage_map(p, threads);
    }
    towers = resolve_towers(p);
    for (const Tower& w : towers) {
      std::array<std::vector<double>, 3> q;
      for (int a = 0; a < 3; ++a) {
        q[a].resize(N[a]);
        for (uint32_t i = 0; i < N[a]; ++i) {
          const double u = (i + 0.5) / N[a];
          q[a][i] = (u - w.center[a]) * (u - w.center[a]) / (w.sigma[a] * w.sigma[a]);
        }
      }
      tower_q.push_back(std::move(q));
    }
    // Voxels a tower can reach: q < 9 needs |u - c| < 3 sigma on each axis, u = (i + 0.5) / N.
    for (const Tower& w : towers) {
      std::array<int64_t, 6> r;
      for (int a = 0; a < 3; ++a) {
        r[a] = int64_t(std::floor((w.center[a] - 3 * w.sigma[a]) * N[a] - 0.5)) - 1;
        r[3 + a] = int64_t(std::ceil((w.center[a] + 3 * w.sigma[a]) * N[a] - 0.5)) + 1;
      }
      tower_box.push_back(r);
    }
  }
  std::vector<std::array<int64_t, 6>> tower_box;  // inclusive voxel bounds (lo xyz, hi xyz), with a margin
  /// Shape factor without noise; the density is R * shape before the threshold.
  float operator()(uint32_t x, uint32_t y, uint32_t z) const {
    if (!field.empty()) return float(field.density({pos[0][x], pos[1][y], pos[2][z]}));
    float prof = columns.top.empty() ? profile[y] : column_profile(p, columns, size_t(z) * N[0] + x, (y + 0.5) / N[1]);
    if (!towers.empty()) {
      // q = sum over axes of ((i + 0.5) / N - c)^2 / sigma^2, in the order x, y, z; the terms are
      // tabulated per axis (same expressions, same bits). Partial sums of non-negative terms never
      // decrease, so a tower is out of reach as soon as one reaches 9.
      double add = 0;
      const double g3 = std::exp(-4.5);  // truncate at 3 sigma so towers are exactly 0 at the edges
      for (size_t i = 0; i < towers.size(); ++i) {
        const double qx = tower_q[i][0][x];
        if (qx >= 9) continue;
        const double qxy = qx + tower_q[i][1][y];
        if (qxy >= 9) continue;
        const double q = qxy + tower_q[i][2][z];
        if (q < 9) add += towers[i].amplitude * (std::exp(-0.5 * q) - g3) / (1 - g3);
      }
      prof += float(add);
    }
    if (!coverage.empty()) prof *= coverage[size_t(z) * N[0] + x];
    return prof;
  }
  std::vector<std::array<std::vector<double>, 3>> tower_q;  // per tower and axis, the term of q per index
  float finish(float r, float s) const {
    float d = r * s;
    return std::clamp((d - t) * inv * scale, 0.0f, 1.0f);
  }
  /// Voxel indices of [lo, hi] (inclusive, may reach one voxel outside the volume) on axis a:
  /// clipped in y and without wrapping, taken modulo in x and z with it.
  std::vector<uint32_t> axis_set(int a, int64_t lo, int64_t hi, bool wrap) const {
    std::vector<uint32_t> v;
    for (int64_t i = lo; i <= hi; ++i) {
      if (i >= 0 && i < int64_t(N[a])) v.push_back(uint32_t(i));
      else if (wrap && a != 1) v.push_back(uint32_t((i % int64_t(N[a]) + N[a]) % int64_t(N[a])));
    }
    return v;
  }
  /// Whether the bound allows density > 0 anywhere in the box [lo, hi] (inclusive; see axis_set).
  /// Exact, and fast where no tower reaches: the shape is then profile(y) * coverage(x, z), and
  /// rounding is monotone, so its maximum is fl(max profile * max coverage).
  bool any_in(const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& hi, bool wrap) const {
    std::vector<uint32_t> c[3];
    for (int a = 0; a < 3; ++a) {
      c[a] = axis_set(a, lo[a], hi[a], wrap);
      if (c[a].empty()) return false;
    }
    if (!field.empty()) return shaped_any(c);
    bool tower = false;
    for (const auto& r : tower_box) {
      bool hit = true;
      for (int a = 0; a < 3 && hit; ++a)
        hit = std::any_of(c[a].begin(), c[a].end(), [&](uint32_t i) { return int64_t(i) >= r[a] && int64_t(i) <= r[3 + a]; });
      tower = tower || hit;
    }
    if (tower) {
      for (uint32_t z : c[2])
        for (uint32_t y : c[1])
          for (uint32_t x : c[0])
            if (finish(1.0f, (*this)(x, y, z)) > 0) return true;
      return false;
    }
    if (!columns.top.empty()) return painted_any(c);
    float pmax = 0, cmax = coverage.empty() ? 1.0f : 0.0f;
    for (uint32_t y : c[1]) pmax = std::max(pmax, profile[y]);
    if (!coverage.empty())
      for (uint32_t z : c[2])
        for (uint32_t x : c[0]) cmax = std::max(cmax, coverage[size_t(z) * N[0] + x]);
    return finish(1.0f, coverage.empty() ? pmax : pmax * cmax) > 0;
  }
  /// any_in for a painted weather map without towers: column profiles are in [0, 1] and 0 where
  /// hn / top >= 1, so none when the lowest row is at or above the highest top (division rounds
  /// monotonically, as column_profile computes it), else fl(profile * coverage) <= max coverage.
  bool painted_any(const std::vector<uint32_t> (&c)[3]) const {
    float cmax = 0, bmax = 0;
    for (uint32_t z : c[2])
      for (uint32_t x : c[0]) {
        cmax = std::max(cmax, coverage[size_t(z) * N[0] + x]);
        bmax = std::max(bmax, columns.top[size_t(z) * N[0] + x]);
      }
    const uint32_t ylo = *std::min_element(c[1].begin(), c[1].end());
    if (!((ylo + 0.5) / N[1] / double(bmax) < 1.0)) return false;
    return finish(1.0f, cmax) > 0;
  }
  /// any_in for shape sources: none where a lower bound of d over the ball around the voxels' box
  /// proves s = 0 (no voxel visited), else voxel by voxel, with the values the bricks compute.
  bool shaped_any(const std::vector<uint32_t> (&c)[3]) const {
    ShapeVec mid;
    double r2 = 0;
    for (int a = 0; a < 3; ++a) {
      const auto [lo, hi] = std::minmax_element(c[a].begin(), c[a].end());
      mid[a] = (pos[a][*lo] + pos[a][*hi]) / 2;
      r2 += (pos[a][*hi] - mid[a]) * (pos[a][*hi] - mid[a]);
    }
    if (field.zero_in_ball(mid, std::sqrt(r2))) return false;
    for (uint32_t z : c[2])
      for (uint32_t y : c[1])
        for (uint32_t x : c[0])
          if (finish(1.0f, (*this)(x, y, z)) > 0) return true;
    return false;
  }
  /// Whether the bound allows density > 0 at a voxel that may lie outside the volume: outside in
  /// y, or in x/z without wrapping, there is nothing; with wrapping x and z are taken modulo.
  bool bound_at(int64_t x, int64_t y, int64_t z, bool wrap) const {
    int64_t c[3] = {x, y, z};
    for (int a = 0; a < 3; ++a) {
      if (c[a] >= 0 && c[a] < int64_t(N[a])) continue;
      if (!wrap || a == 1) return false;
      c[a] = (c[a] % int64_t(N[a]) + N[a]) % int64_t(N[a]);
    }
    return finish(1.0f, (*this)(uint32_t(c[0]), uint32_t(c[1]), uint32_t(c[2]))) > 0;
  }
};

/// Relative cost of one voxel of a channel: octaves weighted by kind (Worley's cell search costs
/// about three Perlin octaves).
double channel_cost(const Channel& c) {
  switch (c.kind) {
    case noise3d::Kind::Perlin: return c.octaves;
    case noise3d::Kind::Worley: return 3.0 * c.octaves;
    case noise3d::Kind::PerlinWorley: return c.octaves + 3.0 * (c.worley_octaves ? c.worley_octaves : c.octaves);
  }
  return c.octaves;
}

bool want_detail(const Preset& p, const GenerateOptions& opt) {
  return opt.detail && (p.channels[1].enabled || p.channels[2].enabled || p.channels[3].enabled);
}

void check_region(const Preset& p, const GenerateOptions& opt, std::array<uint32_t, 3>& lo, std::array<uint32_t, 3>& hi) {
  const std::array<uint32_t, 3> N = p.resolution;
  for (int a = 0; a < 3; ++a) {
    const char* ax[3] = {"x", "y", "z"};
    uint32_t o = opt.region_origin[a], e = opt.region_extent[a] ? opt.region_extent[a] : (N[a] > o ? N[a] - o : 0);
    if (o >= N[a] || uint64_t(o) + e > N[a])
      throw InputError(std::string("--region: ") + ax[a] + " range [" + std::to_string(o) + ", " +
                       std::to_string(uint64_t(o) + e) + ") lies outside the volume [0, " + std::to_string(N[a]) + ")");
    lo[a] = o, hi[a] = o + e;
  }
}

template <class F>
void in_arena(int threads, F&& f) {
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(f);
  } else {
    f();
  }
}

}  // namespace

double BrickPlan::total_cost() const {
  double c = 0;
  for (const auto& b : bricks) c += b.cost;
  return c;
}

BrickPlan plan_bricks(const Preset& p, const GenerateOptions& opt, size_t first, size_t count) {
  BrickPlan plan;
  plan.dims = p.resolution;
  check_region(p, opt, plan.region_lo, plan.region_hi);
  plan.detail = want_detail(p, opt);
  const std::array<uint32_t, 3> N = p.resolution;
  std::array<uint32_t, 3> b0, nb;  // bricks meeting the region, aligned to the global grid
  for (int a = 0; a < 3; ++a) {
    b0[a] = plan.region_lo[a] / kBrick;
    nb[a] = (plan.region_hi[a] + kBrick - 1) / kBrick - b0[a];
  }
  plan.bricks.resize(size_t(nb[0]) * nb[1] * nb[2]);
  double detail_cost = 0;
  for (int c = 1; c < 4; ++c)
    if (p.channels[c].enabled) detail_cost += channel_cost(p.channels[c]);
  const double density_cost = channel_cost(p.channels[0]);
  const Shape shape(p, opt.threads);
  const bool wrap = p.tiling;

  auto plan_one = [&](size_t b) {
    const size_t q[3] = {b % nb[0], b / nb[0] % nb[1], b / (size_t(nb[0]) * nb[1])};
    std::array<uint32_t, 3> lo, hi;  // the whole brick, clipped to the volume
    for (int a = 0; a < 3; ++a) {
      lo[a] = uint32_t((b0[a] + q[a]) * kBrick);
      hi[a] = std::min(N[a], uint32_t((b0[a] + q[a] + 1) * kBrick));
    }
    // Density: any voxel of the whole brick above the threshold with R = 1? Detail: the same over
    // the brick grown by one voxel (wrapping x and z if tiling).
    PlannedBrick& pb = plan.bricks[b];
    const std::array<int64_t, 3> ilo{lo[0], lo[1], lo[2]}, ihi{int64_t(hi[0]) - 1, int64_t(hi[1]) - 1, int64_t(hi[2]) - 1};
    pb.density = shape.any_in(ilo, ihi, false);
    bool near = pb.density;
    if (!near && plan.detail && !opt.detail_only_in_cloud)
      near = shape.any_in({ilo[0] - 1, ilo[1] - 1, ilo[2] - 1}, {ihi[0] + 1, ihi[1] + 1, ihi[2] + 1}, wrap);
    pb.detail = plan.detail && near;
    for (int a = 0; a < 3; ++a) {
      pb.lo[a] = std::max(lo[a], plan.region_lo[a]);
      pb.hi[a] = std::min(hi[a], plan.region_hi[a]);
    }
    const size_t whole = size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    pb.cost = double(whole) * 0.5 + double(pb.count()) * ((pb.density ? density_cost : 0) + (pb.detail ? detail_cost : 0));
  };
  const size_t b_end = first + std::min(count, plan.bricks.size() - std::min(first, plan.bricks.size()));
  for (size_t b = 0; b < plan.bricks.size(); ++b)
    if (b < first || b >= b_end) {  // undecided: the whole brick as if it held cloud
      const size_t q[3] = {b % nb[0], b / nb[0] % nb[1], b / (size_t(nb[0]) * nb[1])};
      for (int a = 0; a < 3; ++a) {
        plan.bricks[b].lo[a] = std::max(plan.region_lo[a], uint32_t((b0[a] + q[a]) * kBrick));
        plan.bricks[b].hi[a] = std::min(plan.region_hi[a], uint32_t((b0[a] + q[a] + 1) * kBrick));
      }
      plan.bricks[b].detail = plan.detail;
    }
  in_arena(opt.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(first, std::max(first, b_end), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t b = r.begin(); b != r.end(); ++b) plan_one(b);
    });
  });
  return plan;
}

Volume volume_header(const Preset& p, const BrickPlan& plan) {
  Volume v;
  for (int a = 0; a < 3; ++a) v.dims[a] = plan.region_hi[a] - plan.region_lo[a];
  v.voxel_size = p.voxel_size;
  for (int a = 0; a < 3; ++a) v.origin[a] = p.origin[a] + plan.region_lo[a] * p.voxel_size;
  v.tiles_xz = p.tiling && v.dims[0] == plan.dims[0] && v.dims[2] == plan.dims[2];
  v.occupancy_cell = p.occupancy_cell;
  v.occupancy_padding = p.occupancy_padding;
  v.metadata = {{"preset", p.name},
                {"seed", std::to_string(p.seed)},
                {"generator", "cloudgen " CLOUDGEN_VERSION},
                {"preset_hash", preset_hash(p)}};
  // The box heights are measured in for the motion (motion.glsl's h): the whole preset's, so a
  // cropped VDB, a tile or a region moves exactly like the full volume (sequence.h motion_box).
  set_motion_height_box(v.metadata, p.origin[1], double(plan.dims[1]) * p.voxel_size);
  // The preset's view travels with every output of every path (one process, MPI, tiles).
  add_view_metadata(v.metadata, p.view);
  // A sub-box says which (the VDB writer keeps the detail on its faces, whose neighbours it
  // cannot see, so tiles merge into exactly the one-process file).
  bool partial = false;
  for (int a = 0; a < 3; ++a) partial |= plan.region_lo[a] != 0 || plan.region_hi[a] != plan.dims[a];
  if (partial)
    v.metadata.push_back({"region", std::to_string(plan.region_lo[0]) + "," + std::to_string(plan.region_lo[1]) + "," +
                                        std::to_string(plan.region_lo[2]) + ":" + std::to_string(v.dims[0]) + "," +
                                        std::to_string(v.dims[1]) + "," + std::to_string(v.dims[2])});
  return v;
}

namespace {

/// The noise grid of box `bx` in a volume of `N` voxels.
noise3d::GridRegion grid_of(const std::array<uint32_t, 3>& N, const PlannedBrick& bx) {
  noise3d::GridRegion g;
  g.size = N;
  g.origin = bx.lo;
  for (int a = 0; a < 3; ++a) g.extent[a] = bx.hi[a] - bx.lo[a];
  return g;
}

/// What execute_plan's workers count, together (they run in parallel).
struct PlanCounters {
  std::atomic<size_t> done{0}, skipped{0}, detail_done{0}, active{0}, noise_cached{0}, noise_evaluated{0};
  std::array<std::atomic<size_t>, kBrickWorkKinds> work_n{};
  std::array<std::atomic<int64_t>, kBrickWorkKinds> work_ns{};

  void report(size_t bricks, std::chrono::steady_clock::time_point t_start, GenerateStats& stats) const {
    stats.bricks = bricks;
    stats.bricks_skipped = skipped;
    stats.detail_bricks = detail_done;
    stats.active_voxels = active;
    stats.noise_cached = noise_cached;
    stats.noise_evaluated = noise_evaluated;
    for (int k = 0; k < kBrickWorkKinds; ++k) {
      stats.work_bricks[k] = work_n[k];
      stats.work_seconds[k] = work_ns[k] * 1e-9;
    }
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  }
};

// Detail blocks keep whole 16-voxel rows: the noise kernel costs 1.3-2x more per voxel on 8-wide
// rows than on 16-wide ones, which eats what smaller blocks would save.
constexpr uint32_t kBlock[3] = {kBrick, kDetailBlock, kDetailBlock};

/// A brick's detail blocks (aligned like the bricks), n[a] per axis, and which keep their noise.
struct DetailBlocks {
  uint32_t n[3];
  std::vector<uint8_t> keep;
  size_t index(uint32_t kx, uint32_t ky, uint32_t kz) const { return (size_t(kz) * n[1] + ky) * n[0] + kx; }
};

}  // namespace

// The cache's stores: one per channel noise (its parameters and the volume's size, the text of
// cache_key), one slot per box: a whole brick for the density channel, a detail block (kBlock,
// up to kBlocksPerBrick per brick) for a detail channel. A run touches only its bricks' slots and
// each brick is one worker's, so workers write slots without locking; the map itself changes only
// before and after the parallel part.
constexpr size_t kBlocksPerBrick = size_t(kBrick / kBlock[0]) * (kBrick / kBlock[1]) * (kBrick / kBlock[2]);

struct NoiseCache::Impl {
  struct Store {
    std::vector<std::vector<float>> boxes;  // slot -> the box's raw noise (empty: not evaluated)
    bool used = false;                      // by the current run
  };
  std::map<std::string, Store> stores;
  std::vector<float> spare[4];  // channel buffers of a returned volume (recycle), reused by the next run
};

NoiseCache::NoiseCache() : impl_(std::make_unique<Impl>()) {}
NoiseCache::~NoiseCache() = default;

size_t NoiseCache::bytes() const {
  size_t b = 0;
  for (const auto& [key, store] : impl_->stores)
    for (const std::vector<float>& box : store.boxes) b += box.size() * sizeof(float);
  return b;
}

void NoiseCache::clear() {
  impl_->stores.clear();
  for (std::vector<float>& s : impl_->spare) s = {};
}

void NoiseCache::recycle(Volume&& v) {
  impl_->spare[0] = std::move(v.density);
  for (int c = 0; c < 3; ++c) impl_->spare[c + 1] = std::move(v.detail[c]);
}

namespace {

/// What a channel's raw noise depends on: its libnoise3d parameters and the volume's size (the
/// lattice positions of the voxels), nothing applied after the noise. `boxes`: "brick" or "block".
std::string cache_key(const noise3d::FractalParams& f, const std::array<uint32_t, 3>& N, const char* boxes) {
  std::ostringstream o;
  o << std::hexfloat << boxes << ';' << int(f.kind) << ';' << f.period.x << ',' << f.period.y << ',' << f.period.z
    << ';' << f.seed << ';' << f.octaves << ';' << f.gain << ';' << f.lacunarity << ';' << f.worley_octaves << ';'
    << f.blend << ';' << N[0] << ',' << N[1] << ',' << N[2];
  return o.str();
}

/// The cache's stores of one run, one per channel (null: not cached), and the drop of the others
/// when the run ends.
class CacheRun {
 public:
  CacheRun(const Preset& p, const BrickPlan& plan, const GenerateOptions& opt) : cache_(opt.noise_cache) {
    bool whole = true;
    for (int a = 0; a < 3; ++a) whole &= plan.region_lo[a] == 0 && plan.region_hi[a] == plan.dims[a];
    if (!cache_ || !whole || !opt.skip_empty) {
      cache_ = nullptr;
      return;
    }
    const std::array<uint32_t, 3> N = p.resolution;
    size_t bricks = 1;
    for (int a = 0; a < 3; ++a) bricks *= (N[a] + kBrick - 1) / kBrick;
    auto& stores = cache_->impl().stores;
    for (auto& [key, store] : stores) store.used = false;
    for (int c = 0; c < 4; ++c) {
      if (c > 0 && !(plan.detail && p.channels[c].enabled)) continue;
      NoiseCache::Impl::Store& st = stores[cache_key(channel_params(p, c), N, c == 0 ? "brick" : "block")];
      st.boxes.resize(c == 0 ? bricks : bricks * kBlocksPerBrick);
      st.used = true;
      store[c] = &st;
    }
    // The noise-free shape (Shape::operator()) of each brick: everything but what the shape does
    // not read (the channels, the threshold, the density), through the one hash of the fields
    // that change generated values, so a threshold or density edit keeps it.
    Preset q = p;
    q.channels = Preset{}.channels;
    q.threshold = Preset{}.threshold;
    q.density_scale = Preset{}.density_scale;
    NoiseCache::Impl::Store& st = stores["shape;" + preset_hash(q)];
    st.boxes.resize(bricks);
    st.used = true;
    shape = &st;
  }
  /// Drops the noise this run did not use (an old seed's, another resolution's).
  ~CacheRun() {
    if (!cache_) return;
    auto& stores = cache_->impl().stores;
    for (auto it = stores.begin(); it != stores.end();) it = it->second.used ? std::next(it) : stores.erase(it);
  }
  std::array<NoiseCache::Impl::Store*, 4> store{};
  NoiseCache::Impl::Store* shape = nullptr;  ///< the shape factor per brick

 private:
  NoiseCache* cache_;
};

/// One brick of execute_plan: density on the whole brick, then each detail channel on the blocks
/// the detail rule keeps; the sink receives the part of the brick in the region.
class BrickWorker {
 public:
  BrickWorker(const Preset& p, const BrickPlan& plan, const GenerateOptions& opt, const BrickSink& sink, size_t n,
              PlanCounters& counters, const CacheRun& cache)
      : p_(p), plan_(plan), opt_(opt), sink_(sink), n_(n), c_(counters), N_(p.resolution),
        rp_(channel_params(p, 0)), shape_(p, opt.threads), cache_(cache) {}

  /// Generates brick `b` and hands it to the sink; `noise` is the calling thread's scratch.
  void run(size_t b, std::vector<float>& noise) {
    const auto t0 = std::chrono::steady_clock::now();
    const PlannedBrick& bx = plan_.bricks[b];
    // The whole brick (density is evaluated on all of it, so what the detail rule sees does not
    // depend on the region), and the part of it in the region, which is what the sink receives.
    PlannedBrick wb = bx;
    for (int a = 0; a < 3; ++a) wb.lo[a] = bx.lo[a] / kBrick * kBrick, wb.hi[a] = std::min(N_[a], wb.lo[a] + kBrick);
    BrickResult res;
    res.density.assign(bx.count(), 0.0f);
    std::vector<float> dens;  // whole brick
    if (bx.density || !opt_.skip_empty) dens = density(bx, wb, noise, res);
    if (!bx.density && opt_.skip_empty) ++c_.skipped;
    if (plan_.detail && (bx.detail || !opt_.skip_empty)) {
      const DetailBlocks blocks = detail_blocks(bx, wb, dens);
      const bool some = std::any_of(blocks.keep.begin(), blocks.keep.end(), [](uint8_t k) { return k != 0; });
      if (some || !opt_.skip_empty) ++c_.detail_done;
      for (int c = 1; c < 4; ++c)
        if (p_.channels[c].enabled) detail_channel(c, bx, wb, blocks, noise, res.detail[c - 1]);
    }
    res.any_value = res.any_density;
    for (int c = 0; c < 3 && !res.any_value; ++c)
      res.any_value = std::any_of(res.detail[c].begin(), res.detail[c].end(), [](float x) { return x != 0; });
    const BrickWork kind = !bx.density ? (bx.detail ? BrickWork::DetailOnly : BrickWork::Skipped)
                                       : (res.any_density ? BrickWork::Cloud : BrickWork::Empty);
    sink_(b, res);
    c_.work_n[int(kind)]++;
    c_.work_ns[int(kind)] +=
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count();
    const size_t d = ++c_.done;
    if (opt_.progress && (d % 16 == 0 || d == n_)) opt_.progress(double(d) / n_);
    if (opt_.cancel && opt_.cancel->load()) throw Cancelled();
  }

 private:
  /// The density of the whole brick `wb` (returned); its region part `bx` goes into res.
  std::vector<float> density(const PlannedBrick& bx, const PlannedBrick& wb, std::vector<float>& noise,
                             BrickResult& res) {
    const uint32_t W[3] = {wb.hi[0] - wb.lo[0], wb.hi[1] - wb.lo[1], wb.hi[2] - wb.lo[2]};
    auto widx = [&](uint32_t x, uint32_t y, uint32_t z) {
      return (size_t(z - wb.lo[2]) * W[1] + (y - wb.lo[1])) * W[0] + (x - wb.lo[0]);
    };
    const Channel& rc = p_.channels[0];
    std::vector<float> dens(wb.count());
    const float* raw = noise_of(rp_, cache_.store[0], brick_slot(wb), grid_of(N_, wb), wb.count(), noise);
    if (cache_.shape) {  // the shape factor kept per brick (the same values as shape_(x, y, z))
      std::vector<float>& shp = cache_.shape->boxes[brick_slot(wb)];
      if (shp.size() != wb.count()) {
        shp.resize(wb.count());
        size_t q = 0;
        for (uint32_t z = wb.lo[2]; z < wb.hi[2]; ++z)
          for (uint32_t y = wb.lo[1]; y < wb.hi[1]; ++y)
            for (uint32_t x = wb.lo[0]; x < wb.hi[0]; ++x, ++q) shp[q] = shape_(x, y, z);
      }
      for (size_t q = 0; q < dens.size(); ++q) dens[q] = shape_.finish(channel_value(rc, raw[q]), shp[q]);
    } else {
      size_t q = 0;
      for (uint32_t z = wb.lo[2]; z < wb.hi[2]; ++z)
        for (uint32_t y = wb.lo[1]; y < wb.hi[1]; ++y)
          for (uint32_t x = wb.lo[0]; x < wb.hi[0]; ++x, ++q)
            dens[q] = shape_.finish(channel_value(rc, raw[q]), shape_(x, y, z));
    }
    size_t k = 0, act = 0;
    for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
      for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y)
        for (uint32_t x = bx.lo[0]; x < bx.hi[0]; ++x, ++k) act += (res.density[k] = dens[widx(x, y, z)]) > 0;
    res.any_density = act > 0;
    c_.active += act;
    return dens;
  }

  /// Detail blocks (16x8x8, aligned like the bricks) that keep their noise: those within one voxel
  /// of this brick's density > 0 or, beyond the brick's faces, of the bound > 0.
  DetailBlocks detail_blocks(const PlannedBrick& bx, const PlannedBrick& wb, const std::vector<float>& dens) const {
    const uint32_t W[3] = {wb.hi[0] - wb.lo[0], wb.hi[1] - wb.lo[1], wb.hi[2] - wb.lo[2]};
    const uint32_t* S = kBlock;
    DetailBlocks blocks{{(W[0] + S[0] - 1) / S[0], (W[1] + S[1] - 1) / S[1], (W[2] + S[2] - 1) / S[2]}, {}};
    const uint32_t* nbk = blocks.n;
    blocks.keep.assign(static_cast<size_t>(nbk[0]) * nbk[1] * nbk[2], 0);
    if (!bx.detail) return blocks;
    const int64_t M[3] = {W[0] + 2, W[1] + 2, W[2] + 2};  // the brick and its one-voxel shell
    const std::vector<uint8_t> maybe = maybe_cloud(wb, dens);
    for (uint32_t kz = 0; kz < nbk[2]; ++kz)
      for (uint32_t ky = 0; ky < nbk[1]; ++ky)
        for (uint32_t kx = 0; kx < nbk[0]; ++kx) {
          bool any = false;  // the block dilated by one voxel (or not), in maybe's coordinates
          const uint32_t d0 = opt_.detail_only_in_cloud ? 1 : 0, d1 = opt_.detail_only_in_cloud ? 0 : 1;
          for (uint32_t z = kz * S[2] + d0; z <= std::min(W[2], (kz + 1) * S[2]) + d1 && !any; ++z)
            for (uint32_t y = ky * S[1] + d0; y <= std::min(W[1], (ky + 1) * S[1]) + d1 && !any; ++y)
              for (uint32_t x = kx * S[0] + d0; x <= std::min(W[0], (kx + 1) * S[0]) + d1 && !any; ++x)
                any = maybe[size_t((z * M[1] + y) * M[0] + x)];
          blocks.keep[blocks.index(kx, ky, kz)] = any;
        }
    return blocks;
  }

  /// 1 where the whole brick `wb` and its one-voxel shell may hold cloud: density > 0 inside, the
  /// bound > 0 in the shell (0 there when detail is read only where density > 0).
  std::vector<uint8_t> maybe_cloud(const PlannedBrick& wb, const std::vector<float>& dens) const {
    const uint32_t W[3] = {wb.hi[0] - wb.lo[0], wb.hi[1] - wb.lo[1], wb.hi[2] - wb.lo[2]};
    const int64_t M[3] = {W[0] + 2, W[1] + 2, W[2] + 2};
    std::vector<uint8_t> maybe(size_t(M[0] * M[1] * M[2]), 0);
    for (int64_t z = -1; z <= W[2]; ++z)
      for (int64_t y = -1; y <= W[1]; ++y)
        for (int64_t x = -1; x <= W[0]; ++x) {
          const bool inside = x >= 0 && y >= 0 && z >= 0 && x < W[0] && y < W[1] && z < W[2];
          uint8_t m;
          if (inside) m = !dens.empty() && dens[(size_t(z) * W[1] + y) * W[0] + x] > 0;
          else if (opt_.detail_only_in_cloud) m = 0;  // read only where density > 0: no shell
          else m = shape_.bound_at(int64_t(wb.lo[0]) + x, int64_t(wb.lo[1]) + y, int64_t(wb.lo[2]) + z, p_.tiling);
          maybe[size_t(((z + 1) * M[1] + (y + 1)) * M[0] + (x + 1))] = m;
        }
    return maybe;
  }

  /// Detail channel c over the region part `bx` into `out`: noise in the kept blocks, 0 elsewhere
  /// (emptied when no block is kept).
  void detail_channel(int c, const PlannedBrick& bx, const PlannedBrick& wb, const DetailBlocks& blocks,
                      std::vector<float>& noise, std::vector<float>& out) const {
    const noise3d::FractalParams cp = channel_params(p_, c);
    const size_t cnt = bx.count();
    out.assign(cnt, 0.0f);
    if (!opt_.skip_empty) {  // evaluate everything, keep what the rule keeps: same bytes
      noise.resize(cnt);
      noise3d::evaluate_grid(cp, grid_of(N_, bx), noise.data(), {1});
    }
    const uint32_t bw = bx.hi[0] - bx.lo[0], bh = bx.hi[1] - bx.lo[1];
    auto at_out = [&](uint32_t x, uint32_t y, uint32_t z) {
      return (size_t(z - bx.lo[2]) * bh + (y - bx.lo[1])) * bw + (x - bx.lo[0]);
    };
    size_t n_kept = 0;
    std::vector<float> scratch;
    for (uint32_t kz = 0; kz < blocks.n[2]; ++kz)
      for (uint32_t ky = 0; ky < blocks.n[1]; ++ky)
        for (uint32_t kx = 0; kx < blocks.n[0]; ++kx) {
          if (!blocks.keep[blocks.index(kx, ky, kz)]) continue;
          PlannedBrick blk;  // the block, clipped to the region part of the brick
          const uint32_t k3[3] = {kx, ky, kz};
          for (int a = 0; a < 3; ++a) {
            blk.lo[a] = std::max(bx.lo[a], wb.lo[a] + k3[a] * kBlock[a]);
            blk.hi[a] = std::min(bx.hi[a], wb.lo[a] + (k3[a] + 1) * kBlock[a]);
          }
          if (blk.lo[0] >= blk.hi[0] || blk.lo[1] >= blk.hi[1] || blk.lo[2] >= blk.hi[2]) continue;
          ++n_kept;
          if (opt_.skip_empty) {
            const float* part = noise_of(cp, cache_.store[c], brick_slot(wb) * kBlocksPerBrick + blocks.index(kx, ky, kz),
                                         grid_of(N_, blk), blk.count(), scratch);
            size_t k = 0;
            for (uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
              for (uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y)
                for (uint32_t x = blk.lo[0]; x < blk.hi[0]; ++x, ++k)
                  out[at_out(x, y, z)] = channel_value(p_.channels[c], part[k]);
          } else {
            for (uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
              for (uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y)
                for (uint32_t x = blk.lo[0]; x < blk.hi[0]; ++x)
                  out[at_out(x, y, z)] = channel_value(p_.channels[c], noise[at_out(x, y, z)]);
          }
        }
    if (!n_kept) out.clear();
  }

  /// The brick's index in the volume's brick grid (x fastest): its slot in the cache.
  size_t brick_slot(const PlannedBrick& wb) const {
    const size_t nx = (N_[0] + kBrick - 1) / kBrick, ny = (N_[1] + kBrick - 1) / kBrick;
    return (size_t(wb.lo[2] / kBrick) * ny + wb.lo[1] / kBrick) * nx + wb.lo[0] / kBrick;
  }

  /// The raw noise of `f` over box `g` (n values): the cache's slot when it holds it, else
  /// evaluated, into the slot (cached) or into `scratch`.
  const float* noise_of(const noise3d::FractalParams& f, NoiseCache::Impl::Store* store, size_t slot,
                        const noise3d::GridRegion& g, size_t n, std::vector<float>& scratch) const {
    std::vector<float>& box = store ? store->boxes[slot] : scratch;
    if (store && box.size() == n) {
      ++c_.noise_cached;
      return box.data();
    }
    box.resize(n);
    noise3d::evaluate_grid(f, g, box.data(), {1});
    if (store) ++c_.noise_evaluated;
    return box.data();
  }

  const Preset& p_;
  const BrickPlan& plan_;
  const GenerateOptions& opt_;
  const BrickSink& sink_;
  const size_t n_;  ///< bricks in this run, for the progress
  PlanCounters& c_;
  const std::array<uint32_t, 3> N_;
  const noise3d::FractalParams rp_;
  const Shape shape_;
  const CacheRun& cache_;
};

}  // namespace

void execute_plan(const Preset& p, const BrickPlan& plan, const std::vector<size_t>* which,
                  const GenerateOptions& opt, const BrickSink& sink, GenerateStats* stats) {
  const auto t_start = std::chrono::steady_clock::now();
  if (plan.dims != p.resolution) throw Error("execute_plan: the plan was made for another resolution");
  const size_t n = which ? which->size() : plan.bricks.size();
  PlanCounters counters;
  const CacheRun cache(p, plan, opt);
  BrickWorker worker(p, plan, opt, sink, n, counters, cache);
  in_arena(opt.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
      std::vector<float> noise;
      for (size_t i = r.begin(); i != r.end(); ++i) worker.run(which ? (*which)[i] : i, noise);
    });
  });
  if (stats) counters.report(n, t_start, *stats);
}

Volume generate(const Preset& p, const GenerateOptions& opt, GenerateStats* stats) {
  const auto t_start = std::chrono::steady_clock::now();
  const BrickPlan plan = plan_bricks(p, opt);
  Volume v = volume_header(p, plan);
  if (opt.noise_cache) {  // the memory of a volume handed back (recycle): no fresh pages to fault in
    std::vector<float>* spare = opt.noise_cache->impl().spare;
    v.density = std::move(spare[0]);
    for (int c = 0; c < 3; ++c) v.detail[c] = std::move(spare[c + 1]);
    for (int c = 0; c < 4; ++c) spare[c] = {};
  }
  v.density.assign(v.voxel_count(), 0.0f);
  for (int c = 1; c < 4; ++c)
    if (plan.detail && p.channels[c].enabled) v.detail[c - 1].assign(v.voxel_count(), 0.0f);
    else v.detail[c - 1] = {};
  const std::array<uint32_t, 3> r0 = plan.region_lo;
  // Bricks are disjoint, so workers write their boxes of the dense channels without locking.
  auto into_volume = [&](size_t b, BrickResult& res) {
    const PlannedBrick& bx = plan.bricks[b];
    const uint32_t w = bx.hi[0] - bx.lo[0];
    auto copy = [&](const std::vector<float>& src, std::vector<float>& dst) {
      size_t k = 0;
      for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
        for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y, k += w)
          std::copy_n(&src[k], w, &dst[v.index(bx.lo[0] - r0[0], y - r0[1], z - r0[2])]);
    };
    copy(res.density, v.density);
    for (int c = 0; c < 3; ++c)
      if (!res.detail[c].empty()) copy(res.detail[c], v.detail[c]);
  };
  execute_plan(p, plan, nullptr, opt, into_volume, stats);
  if (opt.occupancy) build_occupancy(v);
  if (stats) {
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  }
  return v;
}

uint64_t memory_estimate(const Preset& p, bool need_detail) {
  const uint64_t voxels = uint64_t(p.resolution[0]) * p.resolution[1] * p.resolution[2];
  int channels = 1;
  if (need_detail)
    for (int c = 1; c < 4; ++c) channels += p.channels[c].enabled;
  // Dense float channels + one float scratch of the Perlin-Worley accumulator per brick (small),
  // plus the OpenVDB tree when exporting (about the size of the active voxels again).
  return voxels * 4 * (channels + 1);
}

namespace {

void hash_shape(std::ostream& o, const ShapeParams& s) {
  auto vec = [&](const std::optional<ShapeVec>& v) {
    if (v) o << (*v)[0] << ',' << (*v)[1] << ',' << (*v)[2] << ',';
    else o << "-,";
  };
  o << "shape:" << s.blend << ',' << s.falloff << ';';
  if (s.floor || s.ceiling)  // presets without cuts keep their hash
    o << "cut:" << (s.floor ? *s.floor : -1e300) << ',' << (s.ceiling ? *s.ceiling : 1e300) << ';';
  for (const ShapeSource& src : s.sources) {
    o << (src.kind ? shape_kind_name(*src.kind) : "-") << ',';
    vec(src.center), vec(src.radii), vec(src.a), vec(src.b);
    if (src.radius) o << *src.radius << ',';
    else o << "-,";
    vec(src.translate), vec(src.rotate), vec(src.scale);
    if (src.mesh)  // the mesh's content, not its name; a fitted one's placement follows from the volume
      o << "mesh:" << src.mesh->fnv1a << ',' << src.mesh->triangles.size() << ',' << src.fit << ',';
    if (src.vdb)  // the file's seal, grid, iso and up axis, not its name
      o << "vdb:" << src.vdb->fnv1a << ',' << src.fit << ',';
    o << ';';
  }
  for (const ShapeModifier* m : {&s.billowy, &s.wispy}) {  // presets without modifiers keep their hash
    if (!m->on()) continue;
    o << (m == &s.billowy ? "billowy:" : "wispy:") << m->amplitude << ',' << m->period << ',' << m->octaves << ','
      << m->gain << ',' << m->depth << ',';
    if (m->heights) o << (*m->heights)[0] << ',' << (*m->heights)[1] << ',';
    if (m == &s.wispy) o << m->warp << ',' << m->wind[0] << ',' << m->wind[1] << ',' << m->wind[2] << ',' << m->downwind << ',';
    o << ';';
  }
}

}  // namespace

std::string preset_hash(const Preset& p) {
  // FNV-1a over a text rendering of every value-changing field (hex floats: exact). A new Preset
  // field that changes generated values must be added here.
  std::ostringstream o;
  o << std::hexfloat;
  o << p.seed << ';' << p.resolution[0] << ',' << p.resolution[1] << ',' << p.resolution[2] << ';' << p.voxel_size << ';'
    << p.origin[0] << ',' << p.origin[1] << ',' << p.origin[2] << ';' << p.tiling << ';';
  for (const Channel& c : p.channels)
    o << c.enabled << ',' << int(c.kind) << ',' << c.period[0] << ',' << c.period[1] << ',' << c.period[2] << ','
      << c.octaves << ',' << c.gain << ',' << c.lacunarity << ',' << c.worley_octaves << ',' << c.blend << ','
      << c.invert << ',' << c.remap[0] << ',' << c.remap[1] << ',' << c.seed_offset << ';';
  o << height_profile_name(p.height_profile) << ',' << p.height_a << ',' << p.height_b << ',' << p.height_normalize << ';';
  for (const Tower& t : resolve_towers(p))
    for (int a = 0; a < 3; ++a) o << t.center[a] << ',' << t.sigma[a] << ',' << t.amplitude << ';';
  o << p.coverage_enabled << ',' << int(p.coverage_kind) << ',' << p.coverage_period << ',' << p.coverage_octaves << ','
    << p.coverage_low << ',' << p.coverage_high << ';' << p.threshold << ',' << p.density_scale << ';'
    << p.occupancy_cell << ',' << p.occupancy_padding << ';';
  if (!p.shape.sources.empty()) hash_shape(o, p.shape);  // presets without sources keep their hash
  if (p.coverage_image && p.weather_map)  // presets without an image keep their hash
    o << "weather:" << p.weather_map->fnv1a << ',' << p.weather_map->width << ',' << p.weather_map->height << ','
      << p.weather_map->channels << ';';
  const ExportOptions& e = p.export_options;
  o << e.vdb_half << ',' << e.vdb_detail << ',' << e.vdb_up << ',' << e.vdb_physical << ',' << e.vdb_bake_erosion << ';';
  if (e.nvdb_precision != NvdbPrecision::Float)  // float .nvdb presets keep their hash
    o << "nvdb:" << nvdb_precision_name(e.nvdb_precision) << ','
      << (e.nvdb_precision == NvdbPrecision::FpN ? e.nvdb_tolerance : 0.0) << ';';
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char ch : o.str()) h = (h ^ ch) * 0x100000001b3ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

Volume generate_from_file(const std::string& path, const std::vector<std::string>& overrides, int threads) {
  Preset p = load_preset(path, overrides);
  GenerateOptions o;
  o.threads = threads;
  return generate(p, o);
}

}  // namespace cloudgen
