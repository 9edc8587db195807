// Batch evaluation of fractal noise over one tile (or a sub-box of it).
//
// Why it is fast:
//  - Sample positions i*P/N are split exactly in integers into (lattice cell, fraction), once per
//    axis and octave. Lattice indices needed by the region are listed once per axis ("lattice
//    lists"), so a sample's neighbouring lattice points are consecutive list entries and large
//    periods cost nothing extra.
//  - Perlin: the trilinear blend is linear in the corner values, and each corner value is linear in
//    the offset. So for one row (fixed y, z) the noise within an x-cell is
//        lerp(u, A[a]*fx + B[a], A[a+1]*(fx-1) + B[a+1])
//    with per-lattice-point coefficients A, B that fold in the y/z gradients and weights. Those are
//    built per slice (z) and per row (y) from hashed gradient planes cached across slices; the
//    per-sample loop is then 4 loads and 6 flops, which the compiler vectorises.
//  - Worley: per row, for each x lattice point and each of the 9 (y, z) neighbour cells, the
//    feature point's x offset and its partial squared distance in y and z are precomputed; the
//    per-sample loop is 27 x (load, sub, mul, add, min). A sample whose 3x3x3 F1 is further than
//    the nearest cell outside the 3x3x3 block (rare) falls back to the exact point search.
// Each sample's value depends only on its own position, so any threading or sub-box gives the
// same bytes.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <cmath>
#include <limits>
#include <vector>

#include "detail.h"
#include "fractal_detail.h"
#include "noise3d/noise3d.h"

namespace noise3d {

std::array<uint32_t, 3> GridRegion::resolved_extent() const {
  std::array<uint32_t, 3> e{};
  for (int a = 0; a < 3; ++a) e[a] = extent[a] ? extent[a] : (size[a] > origin[a] ? size[a] - origin[a] : 0);
  return e;
}
size_t GridRegion::count() const {
  auto e = resolved_extent();
  return size_t(e[0]) * e[1] * e[2];
}

namespace {

using namespace detail;

/// 64-byte vectors (16 floats / 8 doubles) for the Worley run kernel; kLanes pads the axis arrays.
typedef float VecF __attribute__((vector_size(64)));
typedef double VecD __attribute__((vector_size(64)));
template <class T>
using VecOf = std::conditional_t<std::is_same_v<T, float>, VecF, VecD>;
constexpr int kLanes = 16;

/// One axis of one octave: per sample its cell's index in the lattice list and its fraction.
template <class T>
struct Axis {
  std::vector<uint32_t> m;    ///< index of the sample's cell in `lat`
  std::vector<T> f;           ///< fraction in [0, 1)
  std::vector<T> u;           ///< fade(f)
  std::vector<int64_t> cell;  ///< unwrapped cell (for the exact Worley fallback)
  std::vector<uint32_t> lat;  ///< wrapped lattice index of each list entry
  /// Runs of consecutive samples in the same cell: samples [run[r], run[r+1]) share cell m[run[r]].
  /// The kernels loop over runs with the cell's constants broadcast, which vectorises without gathers.
  std::vector<uint32_t> run;
  /// Signed copies of m for the gather path (high octaves, where runs are 1-2 samples long).
  std::vector<int32_t> mi;
  /// Samples per cell when the lattice repeats exactly along the axis (the tile size a multiple of
  /// the period): sample i + stride is then in the next list entry with the same fraction, for every
  /// i. 0 otherwise. The Worley kernel uses it for short runs: the samples of one residue class
  /// i mod stride read consecutive lattice entries with one shared fraction, a gather-free loop.
  uint32_t stride = 0;
  bool short_runs() const { return run.size() > 1 && m.size() < 6 * (run.size() - 1); }
};

/// lo/hi: how many lattice neighbours below/above the cell each sample needs (Perlin 0/1, Worley 1/1).
template <class T>
Axis<T> make_axis(uint32_t size, uint32_t origin, uint32_t extent, uint32_t period, int lo, int hi) {
  Axis<T> ax;
  ax.m.resize(extent), ax.f.resize(extent), ax.u.resize(extent), ax.cell.resize(extent);
  std::vector<int64_t> list;
  int64_t last = std::numeric_limits<int64_t>::min();
  for (uint32_t s = 0; s < extent; ++s) {
    const uint64_t num = uint64_t(origin + s) * period;  // < 2^32 * 2^30: no overflow
    const int64_t c = int64_t(num / size);
    ax.f[s] = T(num % size) / T(size);
    ax.u[s] = fade(ax.f[s]);
    ax.cell[s] = c;
    for (int64_t v = c - lo; v <= c + hi; ++v)
      if (v > last) list.push_back(last = v);
    ax.m[s] = uint32_t(list.size() - 1 - hi);  // cells are non-decreasing, so c+hi is the last entry
  }
  ax.lat.resize(list.size());
  for (size_t e = 0; e < list.size(); ++e) ax.lat[e] = wrap(list[e], period);
  for (uint32_t s = 0; s < extent; ++s)
    if (s == 0 || ax.m[s] != ax.m[s - 1]) ax.run.push_back(s);
  ax.run.push_back(extent);
  ax.mi.assign(ax.m.begin(), ax.m.end());
  if (period > 0 && size % period == 0) {
    const uint32_t st = size / period;
    bool ok = st <= extent;
    for (uint32_t s = st; ok && s < extent; ++s) ok = ax.m[s] == ax.m[s - st] + 1 && ax.f[s] == ax.f[s - st];
    if (ok) ax.stride = st;
  }
  ax.f.resize(extent + kLanes, T(0));  // chunked kernels may read up to kLanes past the end
  return ax;
}

template <class T>
struct OctaveSetup {
  Octave oc;
  uint32_t key;
  Axis<T> x, y, z;
};

template <class T>
std::vector<OctaveSetup<T>> setup(const FractalParams& p, Kind which, const GridRegion& r) {
  const auto e = r.resolved_extent();
  const int lo = which == Kind::Worley ? 1 : 0;
  std::vector<OctaveSetup<T>> out;
  for (const Octave& oc : octaves(p, which)) {
    OctaveSetup<T> s;
    s.oc = oc;
    s.key = seed_key(oc.seed, which == Kind::Worley ? 0x3a71u : 0x9e11u);
    s.x = make_axis<T>(r.size[0], r.origin[0], e[0], oc.period.x, lo, 1);
    s.y = make_axis<T>(r.size[1], r.origin[1], e[1], oc.period.y, lo, 1);
    s.z = make_axis<T>(r.size[2], r.origin[2], e[2], oc.period.z, lo, 1);
    out.push_back(std::move(s));
  }
  return out;
}

/// A few hashed lattice planes (one z lattice entry each), reused by consecutive slices.
/// FIFO eviction is safe for the <= 3 planes a slice holds at once because slices are visited in
/// increasing z, so the planes a slice needs are always the most recently inserted ones.
template <class Cell>
struct PlaneCache {
  static constexpr int kSlots = 4;
  uint32_t key[kSlots] = {~0u, ~0u, ~0u, ~0u};
  std::vector<Cell> plane[kSlots];
  int next = 0;
  template <class Fill>
  const Cell* get(uint32_t zentry, Fill&& fill) {
    for (int s = 0; s < kSlots; ++s)
      if (key[s] == zentry) return plane[s].data();
    int s = next;
    next = (next + 1) % kSlots;
    key[s] = zentry;
    fill(plane[s]);
    return plane[s].data();
  }
};

// ---------------------------------------------------------------------------------------------
// Perlin

template <class T>
struct PerlinScratch {
  PlaneCache<uint8_t> planes;
  std::vector<T> gx, gy, cz, A, B;
};

template <class T>
void perlin_slice(const OctaveSetup<T>& s, uint32_t k, T* acc, PerlinScratch<T>& sc) {
  const Axis<T>&X = s.x, &Y = s.y, &Z = s.z;
  const size_t nx = X.lat.size(), ny = Y.lat.size();
  auto plane = [&](uint32_t ze) {
    return sc.planes.get(ze, [&](std::vector<uint8_t>& g) {
      g.resize(nx * ny);
      for (size_t b = 0; b < ny; ++b) {
        const uint32_t row = hash_row(Y.lat[b], Z.lat[ze], s.key);
        uint8_t* dst = &g[b * nx];
        for (size_t a = 0; a < nx; ++a) dst[a] = uint8_t(grad_index(hash_x(row, X.lat[a])));
      }
    });
  };
  const uint32_t mz = Z.m[k];
  const uint8_t* g0 = plane(mz);
  const uint8_t* g1 = plane(mz + 1);
  const T fz = Z.f[k], w = Z.u[k], w0 = T(1) - w, fz1 = fz - T(1);
  sc.gx.resize(nx * ny), sc.gy.resize(nx * ny), sc.cz.resize(nx * ny);
  for (size_t e = 0; e < nx * ny; ++e) {
    const uint8_t a = g0[e], b = g1[e];
    sc.gx[e] = w0 * T(kGradX[a]) + w * T(kGradX[b]);
    sc.gy[e] = w0 * T(kGradY[a]) + w * T(kGradY[b]);
    sc.cz[e] = w0 * (T(kGradZ[a]) * fz) + w * (T(kGradZ[b]) * fz1);
  }
  sc.A.resize(nx), sc.B.resize(nx);
  const size_t ex = X.m.size(), ey = Y.m.size();
  const T wt = T(s.oc.weight);
  const bool gather = X.short_runs();  // about one sample per cell: gather instead of runs
  for (size_t j = 0; j < ey; ++j) {
    const size_t r0 = size_t(Y.m[j]) * nx, r1 = r0 + nx;
    const T fy = Y.f[j], v = Y.u[j], v0 = T(1) - v, fy1 = fy - T(1);
    T* __restrict A = sc.A.data();
    T* __restrict B = sc.B.data();
    const T *gx = sc.gx.data(), *gy = sc.gy.data(), *cz = sc.cz.data();
    for (size_t a = 0; a < nx; ++a) {
      A[a] = v0 * gx[r0 + a] + v * gx[r1 + a];
      B[a] = v0 * (gy[r0 + a] * fy + cz[r0 + a]) + v * (gy[r1 + a] * fy1 + cz[r1 + a]);
    }
    T* __restrict out = acc + j * ex;
    const T* __restrict f = X.f.data();
    const T* __restrict u = X.u.data();
    if (gather) {
      const int32_t* __restrict mi = X.mi.data();
      for (size_t i = 0; i < ex; ++i) {
        const int32_t a = mi[i];
        const T n0 = A[a] * f[i] + B[a];
        const T n1 = A[a + 1] * (f[i] - T(1)) + B[a + 1];
        out[i] += wt * (n0 + u[i] * (n1 - n0));
      }
      continue;
    }
    for (size_t r = 0; r + 1 < X.run.size(); ++r) {
      const uint32_t s0 = X.run[r], s1 = X.run[r + 1], a = X.m[s0];
      const T A0 = A[a], B0 = B[a], A1 = A[a + 1], B1 = B[a + 1];
      for (uint32_t i = s0; i < s1; ++i) {
        const T n0 = A0 * f[i] + B0;
        const T n1 = A1 * (f[i] - T(1)) + B1;
        out[i] += wt * (n0 + u[i] * (n1 - n0));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Worley

template <class T>
struct Jitter {
  T x, y, z;
};

template <class T>
struct WorleyScratch {
  PlaneCache<Jitter<T>> planes;
  std::vector<T> jx, r2;  // [9][nx]
  std::vector<T> best;    // [ex]
  std::vector<T> phase;   // [ex / stride]: one residue class of a repeating lattice
};

template <class T>
void worley_slice(const OctaveSetup<T>& s, uint32_t k, T* acc, WorleyScratch<T>& sc) {
  const Axis<T>&X = s.x, &Y = s.y, &Z = s.z;
  const size_t nx = X.lat.size(), ny = Y.lat.size();
  auto plane = [&](uint32_t ze) {
    return sc.planes.get(ze, [&](std::vector<Jitter<T>>& g) {
      g.resize(nx * ny);
      for (size_t b = 0; b < ny; ++b) {
        const uint32_t row = hash_row(Y.lat[b], Z.lat[ze], s.key);
        Jitter<T>* dst = &g[b * nx];
        for (size_t a = 0; a < nx; ++a) {
          const uint32_t h = hash_x(row, X.lat[a]);
          dst[a] = {jitter01<T>(jitter_hash(h, 0)), jitter01<T>(jitter_hash(h, 1)),
                    jitter01<T>(jitter_hash(h, 2))};
        }
      }
    });
  };
  const uint32_t mz = Z.m[k];
  const Jitter<T>* pl[3] = {plane(mz - 1), plane(mz), plane(mz + 1)};
  const T fz = Z.f[k];
  const size_t ex = X.m.size(), ey = Y.m.size();
  sc.jx.resize(9 * nx), sc.r2.resize(9 * nx), sc.best.resize(ex);
  const T wt = T(s.oc.weight), inv_sqrt3 = T(1.0 / kSqrt3);
  const T fzm = std::min(fz, T(1) - fz);
  const bool gather = X.short_runs();  // about one sample per cell: gather instead of runs
  for (size_t j = 0; j < ey; ++j) {
    const T fy = Y.f[j];
    // Partial distances in y and z of the 9 (y, z) neighbour cells, for every x lattice entry.
    for (int n = 0; n < 9; ++n) {
      const int by = n % 3, bz = n / 3;
      const Jitter<T>* src = pl[bz] + size_t(Y.m[j] + by - 1) * nx;
      const T oy = T(by - 1) - fy, oz = T(bz - 1) - fz;
      T* jx = &sc.jx[n * nx];
      T* r2 = &sc.r2[n * nx];
      for (size_t a = 0; a < nx; ++a) {
        const T dy = oy + src[a].y, dz = oz + src[a].z;
        jx[a] = src[a].x;
        r2[a] = dy * dy + dz * dz;
      }
    }
    T* __restrict best = sc.best.data();
    const T* __restrict f = X.f.data();
    if (gather && X.stride > 0) {
      // About one sample per cell on an exactly repeating lattice: the samples r, r + stride,
      // r + 2 stride, ... share the fraction f[r] and sit in consecutive lattice entries, so each
      // residue class is a contiguous loop over the neighbours' constants (no gathers). The same
      // candidates and operations as the gather loop below, so the same values.
      const uint32_t st = X.stride;
      sc.phase.resize(ex);
      for (uint32_t r = 0; r < st; ++r) {
        const size_t count = (ex - r + st - 1) / st;
        const T fr = f[r];
        const int32_t a0 = X.mi[r];
        T* __restrict b = sc.phase.data();
        for (size_t c = 0; c < count; ++c) b[c] = std::numeric_limits<T>::infinity();
        for (int n = 0; n < 9; ++n) {
          for (int dx = 0; dx < 3; ++dx) {
            const T off = T(dx - 1);
            const T* __restrict jx = sc.jx.data() + n * nx + (a0 + dx - 1);
            const T* __restrict r2 = sc.r2.data() + n * nx + (a0 + dx - 1);
            for (size_t c = 0; c < count; ++c) {
              const T d = jx[c] + off - fr;
              const T d2 = d * d + r2[c];
              b[c] = d2 < b[c] ? d2 : b[c];
            }
          }
        }
        for (size_t c = 0; c < count; ++c) best[r + c * st] = b[c];
      }
    } else if (gather) {
      // About one sample per cell: gather the neighbours' constants per sample instead.
      const int32_t* __restrict mi = X.mi.data();
      for (size_t i = 0; i < ex; ++i) best[i] = std::numeric_limits<T>::infinity();
      for (int n = 0; n < 9; ++n) {
        const T* __restrict jx = sc.jx.data() + n * nx;
        const T* __restrict r2 = sc.r2.data() + n * nx;
        for (int dx = 0; dx < 3; ++dx) {
          const T off = T(dx - 1);
          for (size_t i = 0; i < ex; ++i) {
            const int32_t a = mi[i] + dx - 1;
            const T d = jx[a] + off - f[i];
            const T d2 = d * d + r2[a];
            best[i] = d2 < best[i] ? d2 : best[i];
          }
        }
      }
    } else {
      for (size_t r = 0; r + 1 < X.run.size(); ++r) {
        const uint32_t s0 = X.run[r], s1 = X.run[r + 1], a = X.m[s0];
        // The 27 neighbour feature points of this cell: x offset and y/z partial squared distance.
        T cx[27], rr[27];
        for (int q = 0; q < 27; ++q) {
          const int n = q / 3, dx = q % 3;
          cx[q] = sc.jx[n * nx + a + dx - 1] + T(dx - 1);
          rr[q] = sc.r2[n * nx + a + dx - 1];
        }
        // One 64-byte vector of samples at a time, the running minimum held in a register:
        // GCC/Clang vector extensions, elementwise IEEE operations (same values as scalar code),
        // lowered to AVX-512, AVX2 or SSE as the target allows. `f` is padded by kLanes, so a
        // vector may read past the run; only the run's lanes are stored.
        using V = VecOf<T>;
        constexpr int L = int(sizeof(V) / sizeof(T));
        for (uint32_t c0 = s0; c0 < s1; c0 += L) {
          V fv, m;
          std::memcpy(&fv, f + c0, sizeof(V));
          for (int l = 0; l < L; ++l) m[l] = std::numeric_limits<T>::infinity();
          for (int q = 0; q < 27; ++q) {
            const V d = cx[q] - fv;
            const V d2 = d * d + rr[q];
            m = d2 < m ? d2 : m;
          }
          const uint32_t lanes = std::min<uint32_t>(L, s1 - c0);
          for (uint32_t l = 0; l < lanes; ++l) best[c0 + l] = m[l];
        }
      }
    }
    const T fym = std::min(fy, T(1) - fy);
    T* out = acc + j * ex;
    for (size_t i = 0; i < ex; ++i) {
      T d2 = best[i];
      // Nearest possible point outside the 3x3x3 block is 1 + min over axes of the distance to
      // the cell's nearer face; beyond it the 3x3x3 answer might be wrong, so search exactly.
      const T shell = T(1) + std::min({std::min(f[i], T(1) - f[i]), fym, fzm});
      T f1;
      if (d2 > shell * shell) {
        const double sx = double(X.cell[i]) + double(f[i]), sy = double(Y.cell[j]) + double(fy),
                     sz = double(Z.cell[k]) + double(fz);
        f1 = T(worley(sx, sy, sz, s.oc.period, s.oc.seed).f1);
      } else {
        f1 = std::sqrt(d2);
      }
      out[i] += wt * (T(1) - f1 * inv_sqrt3);
    }
  }
}

template <class T>
MinMax run(const FractalParams& p, const GridRegion& r, T* out, const BatchOptions& opt) {
  validate(p);
  for (int a = 0; a < 3; ++a) {
    const char* ax[3] = {"x", "y", "z"};
    if (r.size[a] < 1)
      throw InvalidParameter(std::string("size.") + ax[a], "must be at least 1");
    const auto e = r.resolved_extent();
    if (uint64_t(r.origin[a]) + e[a] > r.size[a])
      throw InvalidParameter(std::string("region.") + ax[a],
                             "origin + extent must not exceed size " + std::to_string(r.size[a]));
  }
  const auto e = r.resolved_extent();
  if (r.count() == 0) return {0, 0};
  const bool want_p = p.kind != Kind::Worley, want_w = p.kind != Kind::Perlin;
  std::vector<OctaveSetup<T>> po, wo;
  if (want_p) po = setup<T>(p, Kind::Perlin, r);
  if (want_w) wo = setup<T>(p, Kind::Worley, r);
  const size_t slice = size_t(e[0]) * e[1];

  auto body = [&](const tbb::blocked_range<uint32_t>& range) {
    std::vector<PerlinScratch<T>> ps(po.size());
    std::vector<WorleyScratch<T>> ws(wo.size());
    std::vector<T> wacc(want_p && want_w ? slice : 0);
    for (uint32_t k = range.begin(); k != range.end(); ++k) {
      T* dst = out + k * slice;
      std::fill(dst, dst + slice, T(0));
      T* wdst = want_p && want_w ? wacc.data() : dst;
      if (want_p && want_w) std::fill(wacc.begin(), wacc.end(), T(0));
      for (size_t o = 0; o < po.size(); ++o) perlin_slice(po[o], k, dst, ps[o]);
      for (size_t o = 0; o < wo.size(); ++o) worley_slice(wo[o], k, wdst, ws[o]);
      if (want_p && want_w)
        for (size_t q = 0; q < slice; ++q) dst[q] = T(combine_perlin_worley(dst[q], wacc[q], p.blend));
    }
  };
  // Grain of a few slices keeps the plane caches warm; values never depend on the split.
  auto go = [&] { tbb::parallel_for(tbb::blocked_range<uint32_t>(0, e[2], 4), body); };
  if (opt.threads > 0) {
    tbb::task_arena arena(opt.threads);
    arena.execute(go);
  } else {
    go();
  }
  MinMax mm{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  const size_t n = r.count();
  for (size_t q = 0; q < n; ++q) {
    mm.min = std::min(mm.min, double(out[q]));
    mm.max = std::max(mm.max, double(out[q]));
  }
  return mm;
}

}  // namespace

MinMax evaluate_grid(const FractalParams& p, const GridRegion& r, float* out, const BatchOptions& o) {
  return run<float>(p, r, out, o);
}
MinMax evaluate_grid(const FractalParams& p, const GridRegion& r, double* out, const BatchOptions& o) {
  return run<double>(p, r, out, o);
}

}  // namespace noise3d
