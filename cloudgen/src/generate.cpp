// The cloud pipeline, brick by brick.
//
// Skipping is exact: density = clamp(scale * (R * profile * coverage - t) / (1 - t), 0, 1) with the
// noise R in [0, 1]. Float multiplication is monotone, so fl(fl(R*P)*C) <= fl(P*C) for R <= 1:
// a brick whose max of P*C (no noise needed) is <= t is zero everywhere, and its noise is never
// evaluated. Skipped and unskipped runs therefore give the same bytes (tested).
#include "cloudgen/generate.h"

#include "cloudgen/cloud_type.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace cloudgen {
namespace {

double smoothstep(double a, double b, double x) {
  double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

/// Noise value mapped to [0, 1] (Perlin fBm is in [-1, 1]).
float to_unit(noise3d::Kind k, float v) {
  const float u = k == noise3d::Kind::Perlin ? 0.5f + 0.5f * v : v;
  return std::clamp(u, 0.0f, 1.0f);
}
/// A channel's value: to [0, 1], contrast remap (identity for [0, 1] leaves bytes unchanged), invert.
float channel_value(const Channel& ch, float v) {
  float u = to_unit(ch.kind, v);
  if (ch.remap[0] != 0.0 || ch.remap[1] != 1.0) {
    const float lo = float(ch.remap[0]), hi = float(ch.remap[1]);
    u = std::clamp((u - lo) / (hi - lo), 0.0f, 1.0f);
  }
  return ch.invert ? 1.0f - u : u;
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

struct Box {
  std::array<uint32_t, 3> lo, hi;  // voxel range [lo, hi) in volume coordinates
  size_t count() const { return size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
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

Volume generate(const Preset& p, const GenerateOptions& opt, GenerateStats* stats) {
  const auto t_start = std::chrono::steady_clock::now();
  const std::array<uint32_t, 3> N = p.resolution;
  Box region;
  for (int a = 0; a < 3; ++a) {
    const char* ax[3] = {"x", "y", "z"};
    uint32_t o = opt.region_origin[a], e = opt.region_extent[a] ? opt.region_extent[a] : (N[a] > o ? N[a] - o : 0);
    if (o >= N[a] || uint64_t(o) + e > N[a])
      throw InputError(std::string("--region: ") + ax[a] + " range [" + std::to_string(o) + ", " +
                       std::to_string(uint64_t(o) + e) + ") lies outside the volume [0, " + std::to_string(N[a]) + ")");
    region.lo[a] = o, region.hi[a] = o + e;
  }
  Volume v;
  v.dims = {region.hi[0] - region.lo[0], region.hi[1] - region.lo[1], region.hi[2] - region.lo[2]};
  v.voxel_size = p.voxel_size;
  for (int a = 0; a < 3; ++a) v.origin[a] = p.origin[a] + region.lo[a] * p.voxel_size;
  v.tiles_xz = p.tiling && v.dims[0] == N[0] && v.dims[2] == N[2];
  v.occupancy_cell = p.occupancy_cell;
  v.occupancy_padding = p.occupancy_padding;
  v.density.assign(v.voxel_count(), 0.0f);
  v.metadata = {{"preset", p.name}, {"seed", std::to_string(p.seed)}, {"generator", "cloudgen " CLOUDGEN_VERSION}};

  // Per-voxel factors that need no noise: profile by row, coverage by column, towers per voxel.
  std::vector<float> profile(N[1]);
  for (uint32_t y = 0; y < N[1]; ++y) profile[y] = float(height_profile(p, (y + 0.5) / N[1]));
  std::vector<float> coverage;  // [z][x] over the whole x-z plane (2D, cheap), empty = 1
  if (p.coverage_enabled) {
    noise3d::FractalParams cp;
    cp.kind = p.coverage_kind;
    cp.period = {p.coverage_period, 1,
                 std::max<uint32_t>(1, uint32_t(std::lround(double(p.coverage_period) * N[2] / N[0])))};
    cp.octaves = p.coverage_octaves;
    cp.seed = p.seed ^ 0xC0FEC0FEull;
    noise3d::GridRegion g;
    g.size = {N[0], 1, N[2]};
    coverage.resize(g.count());
    noise3d::evaluate_grid(cp, g, coverage.data(), {opt.threads});
    for (float& c : coverage) c = float(smoothstep(p.coverage_low, p.coverage_high, to_unit(cp.kind, c)));
  }
  const std::vector<Tower> towers = resolve_towers(p);
  const float t = float(p.threshold), inv = float(1.0 / (1.0 - p.threshold)), scale = float(p.density_scale);

  // Shape factor without noise at a region voxel; the density is R * shape before the threshold.
  auto shape = [&](uint32_t x, uint32_t y, uint32_t z) -> float {
    float prof = profile[y];
    if (!towers.empty()) {
      double u[3] = {(x + 0.5) / N[0], (y + 0.5) / N[1], (z + 0.5) / N[2]};
      double add = 0;
      const double g3 = std::exp(-4.5);  // truncate at 3 sigma so towers are exactly 0 at the edges
      for (const Tower& w : towers) {
        double q = 0;
        for (int a = 0; a < 3; ++a) q += (u[a] - w.center[a]) * (u[a] - w.center[a]) / (w.sigma[a] * w.sigma[a]);
        if (q < 9) add += w.amplitude * (std::exp(-0.5 * q) - g3) / (1 - g3);
      }
      prof += float(add);
    }
    if (!coverage.empty()) prof *= coverage[size_t(z) * N[0] + x];
    return prof;
  };
  auto finish = [&](float r, float s) -> float {
    float d = r * s;
    return std::clamp((d - t) * inv * scale, 0.0f, 1.0f);
  };

  // Bricks aligned to the global grid. Whether a brick holds cloud decides the detail channels of
  // its neighbours, so the density pass covers the region's bricks plus a one-brick halo and
  // always evaluates whole bricks: a region then gets exactly the full run's values everywhere.
  std::array<uint32_t, 3> b0, nb;
  for (int a = 0; a < 3; ++a) {
    const uint32_t total = (N[a] + kBrick - 1) / kBrick;
    b0[a] = region.lo[a] / kBrick > 0 ? region.lo[a] / kBrick - 1 : 0;
    nb[a] = std::min(total, (region.hi[a] + kBrick - 1) / kBrick + 1) - b0[a];
  }
  const size_t nbricks = size_t(nb[0]) * nb[1] * nb[2];
  auto brick_box = [&](size_t b) {  // whole brick, clipped to the volume
    Box bx;
    size_t q[3] = {b % nb[0], b / nb[0] % nb[1], b / (size_t(nb[0]) * nb[1])};
    for (int a = 0; a < 3; ++a) {
      bx.lo[a] = uint32_t((b0[a] + q[a]) * kBrick);
      bx.hi[a] = std::min(N[a], uint32_t((b0[a] + q[a] + 1) * kBrick));
    }
    return bx;
  };
  auto clip = [&](Box bx) {  // part of a brick inside the region (possibly empty)
    for (int a = 0; a < 3; ++a) {
      bx.lo[a] = std::max(bx.lo[a], region.lo[a]);
      bx.hi[a] = std::max(bx.lo[a], std::min(bx.hi[a], region.hi[a]));
    }
    return bx;
  };
  auto grid_of = [&](const Box& bx) {
    noise3d::GridRegion g;
    g.size = N;
    g.origin = bx.lo;
    for (int a = 0; a < 3; ++a) g.extent[a] = bx.hi[a] - bx.lo[a];
    return g;
  };
  const noise3d::FractalParams rp = channel_params(p, 0);
  const Channel& rc = p.channels[0];
  std::vector<uint8_t> nonempty(nbricks, 0);
  std::atomic<size_t> skipped{0}, done{0}, detail_done{0};
  const bool want_detail = opt.detail && (p.channels[1].enabled || p.channels[2].enabled || p.channels[3].enabled);
  const size_t total_work = nbricks * (want_detail ? 2 : 1);
  auto tick = [&] {
    size_t d = ++done;
    if (opt.progress && (d % 16 == 0 || d == total_work)) opt.progress(double(d) / total_work);
    if (opt.cancel && opt.cancel->load()) throw Cancelled();
  };

  auto density_pass = [&](const tbb::blocked_range<size_t>& range) {
    std::vector<float> shp, noise;
    for (size_t b = range.begin(); b != range.end(); ++b) {
      const Box bx = brick_box(b);
      shp.resize(bx.count());
      float smax = -1;
      size_t q = 0;
      for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
        for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y)
          for (uint32_t x = bx.lo[0]; x < bx.hi[0]; ++x, ++q) smax = std::max(smax, finish(1.0f, shp[q] = shape(x, y, z)));
      if (opt.skip_empty && smax <= 0.0f) {
        ++skipped;
        tick();
        continue;
      }
      noise.resize(bx.count());
      noise3d::evaluate_grid(rp, grid_of(bx), noise.data(), {1});
      q = 0;
      bool any = false;
      const Box in = clip(bx);
      for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
        for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y)
          for (uint32_t x = bx.lo[0]; x < bx.hi[0]; ++x, ++q) {
            const float d = finish(channel_value(rc, noise[q]), shp[q]);
            any |= d > 0;
            if (x >= in.lo[0] && x < in.hi[0] && y >= in.lo[1] && y < in.hi[1] && z >= in.lo[2] && z < in.hi[2])
              v.density[v.index(x - region.lo[0], y - region.lo[1], z - region.lo[2])] = d;
          }
      nonempty[b] = any;
      tick();
    }
  };

  // Detail channels where the brick or a neighbour holds cloud (trilinear filtering at a brick
  // face reads the neighbour); 0 elsewhere, in skipped and unskipped runs alike.
  auto detail_pass = [&](const tbb::blocked_range<size_t>& range) {
    std::vector<float> noise;
    for (size_t b = range.begin(); b != range.end(); ++b) {
      const Box bx = clip(brick_box(b));
      if (bx.count() == 0) {  // halo brick: only its emptiness was needed
        tick();
        continue;
      }
      const int64_t q[3] = {int64_t(b % nb[0]), int64_t(b / nb[0] % nb[1]), int64_t(b / (size_t(nb[0]) * nb[1]))};
      bool near = false;
      for (int dz = -1; dz <= 1 && !near; ++dz)
        for (int dy = -1; dy <= 1 && !near; ++dy)
          for (int dx = -1; dx <= 1 && !near; ++dx) {
            int64_t r[3] = {q[0] + dx, q[1] + dy, q[2] + dz};
            if (r[0] < 0 || r[1] < 0 || r[2] < 0 || r[0] >= nb[0] || r[1] >= nb[1] || r[2] >= nb[2]) continue;
            near = nonempty[size_t((r[2] * nb[1] + r[1]) * nb[0] + r[0])];
          }
      if (near) {
        ++detail_done;
        noise.resize(bx.count());
        for (int c = 1; c < 4; ++c) {
          if (!p.channels[c].enabled) continue;
          noise3d::evaluate_grid(channel_params(p, c), grid_of(bx), noise.data(), {1});
          size_t k = 0;
          for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
            for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y) {
              float* row = &v.detail[c - 1][v.index(bx.lo[0] - region.lo[0], y - region.lo[1], z - region.lo[2])];
              for (uint32_t x = bx.lo[0]; x < bx.hi[0]; ++x, ++k)
                row[x - bx.lo[0]] = channel_value(p.channels[c], noise[k]);
            }
        }
      }
      tick();
    }
  };

  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nbricks, 1), density_pass);
    if (want_detail) {
      for (int c = 1; c < 4; ++c)
        if (p.channels[c].enabled) v.detail[c - 1].assign(v.voxel_count(), 0.0f);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, nbricks, 1), detail_pass);
    }
  };
  if (opt.threads > 0) {
    tbb::task_arena arena(opt.threads);
    arena.execute(run);
  } else {
    run();
  }
  if (opt.occupancy) build_occupancy(v);
  if (stats) {
    stats->bricks = nbricks;
    stats->bricks_skipped = skipped;
    stats->detail_bricks = detail_done;
    stats->active_voxels = size_t(std::count_if(v.density.begin(), v.density.end(), [](float d) { return d > 0; }));
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  }
  return v;
}

Volume generate_from_file(const std::string& path, const std::vector<std::string>& overrides, int threads) {
  Preset p = load_preset(path, overrides);
  GenerateOptions o;
  o.threads = threads;
  return generate(p, o);
}

}  // namespace cloudgen
