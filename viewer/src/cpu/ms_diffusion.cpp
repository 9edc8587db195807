// Multiple scattering by flux-limited diffusion (render.ms_volume; docs/accuracy.md). The light
// that has scattered at least once is diffuse after a few scatterings in a cloud, so its fluence
// phi obeys the diffusion equation (Stam, "Multiple Scattering as a Diffusion Process", EGWR 1995)
//
//   -div(D grad phi) + sigma_a phi = Q,      Q = sigma_s * E_sun * T_sun  (the first-scattering source)
//
// with the similarity relation's reduced extinction sigma_tr = sigma_a + sigma_s (1 - g) for a
// forward-peaked phase function and Wilson's flux limiter D = 1 / (3 sigma_tr + |grad phi| / phi),
// which keeps the flux at or below phi where the medium is thin or empty, so light leaves a thin
// wisp instead of diffusing through it at unbounded speed (Koerner et al., "Flux-Limited Diffusion
// for Multiple Scattering in Participating Media", CGF 2014). Boundaries of the box that do not
// wrap see vacuum: Marshak's condition (extrapolation length 2 D).
//
// Discretisation: finite volumes on the cell centres, the face conductance of two cells the
// harmonic mean of their D, red-black successive over-relaxation with the limiter lagged a few
// sweeps, each grid started from the next coarser one's solution. Every half sweep computes its cells from the previous array, so the result is the
// same bytes at any thread count.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "cloudviewer/renderer.h"

namespace cloudviewer {

namespace {

struct Grid {
  glm::ivec3 n;
  bool tiles;
  size_t index(int x, int y, int z) const { return (size_t(z) * size_t(n.y) + size_t(y)) * size_t(n.x) + size_t(x); }
  // The neighbour's index across face (axis, side), or -1 beyond a boundary that does not wrap.
  long neighbour(int x, int y, int z, int axis, int side) const {
    glm::ivec3 c(x, y, z);
    c[axis] += side;
    if (c[axis] < 0 || c[axis] >= n[axis]) {
      if (!tiles || axis == 1) return -1;
      c[axis] = (c[axis] + n[axis]) % n[axis];
    }
    return long(index(c.x, c.y, c.z));
  }
};

// The limiter is lagged: D is updated from phi every this many sweeps, and between updates the
// problem is linear, where over-relaxed red-black sweeps converge for any factor in (0, 2) (updating
// D at every sweep with over-relaxation overshoots by orders of magnitude before it settles).
constexpr int kSweepsPerLimiter = 4;

// The iteration on one grid from `initial` (empty: zero).
MsDiffusionResult iterate(const MsDiffusionGrid& g, const MsDiffusionOptions& o, std::vector<double> initial) {
  const size_t cells = size_t(g.dims.x) * size_t(g.dims.y) * size_t(g.dims.z);
  const Grid grid{g.dims, g.tiles_xz};
  std::vector<double> sigma_a(cells), sigma_tr(cells), q(cells);
  double q_max = 0;
  for (size_t i = 0; i < cells; ++i) {
    const double st = std::max(g.sigma_t[i], 0.0);
    sigma_a[i] = (1.0 - o.albedo) * st;
    sigma_tr[i] = sigma_a[i] + o.albedo * st * (1.0 - o.asymmetry);
    q[i] = o.albedo * std::max(g.source[i], 0.0);
    q_max = std::max(q_max, q[i]);
  }
  MsDiffusionResult r;
  r.fluence.assign(cells, 0.0);
  if (q_max <= 0) return r;
  if (initial.size() == cells) r.fluence = std::move(initial);  // nothing lit scatters: no multiple scattering
  // D never exceeds the box's diagonal (a zero-gradient region of empty cells would be unbounded).
  const glm::dvec3 size = glm::dvec3(g.dims) * g.cell_m;
  const double d_max = glm::length(size);
  const double h2[3] = {g.cell_m.x * g.cell_m.x, g.cell_m.y * g.cell_m.y, g.cell_m.z * g.cell_m.z};
  std::vector<double>& phi = r.fluence;
  std::vector<double> next(cells, 0.0), diff(cells, 0.0);

  // D per cell from the current phi: Wilson's limiter with the central-difference gradient (one
  // sided at a boundary that does not wrap).
  auto update_diffusion = [&]() {
    tbb::parallel_for(0, g.dims.z, [&](int z) {
      for (int y = 0; y < g.dims.y; ++y)
        for (int x = 0; x < g.dims.x; ++x) {
          const size_t i = grid.index(x, y, z);
          double grad2 = 0;
          for (int a = 0; a < 3; ++a) {
            const long lo = grid.neighbour(x, y, z, a, -1), hi = grid.neighbour(x, y, z, a, +1);
            const double h = g.cell_m[a];
            double d = 0;
            if (lo >= 0 && hi >= 0) d = (phi[size_t(hi)] - phi[size_t(lo)]) / (2 * h);
            else if (hi >= 0) d = (phi[size_t(hi)] - phi[i]) / h;
            else if (lo >= 0) d = (phi[i] - phi[size_t(lo)]) / h;
            grad2 += d * d;
          }
          const double limiter = phi[i] > 0 ? std::sqrt(grad2) / phi[i] : 0.0;
          diff[i] = std::min(1.0 / (3.0 * sigma_tr[i] + limiter), d_max);
          if (!(diff[i] > 0)) diff[i] = d_max;  // no medium and no gradient
        }
    });
  };

  // One half sweep: the cells of one colour from `phi`, into `next` (the others copied).
  auto half_sweep = [&](int colour) {
    tbb::parallel_for(0, g.dims.z, [&](int z) {
      for (int y = 0; y < g.dims.y; ++y)
        for (int x = 0; x < g.dims.x; ++x) {
          const size_t i = grid.index(x, y, z);
          if (((x + y + z) & 1) != colour) {
            next[i] = phi[i];
            continue;
          }
          double num = q[i], den = sigma_a[i];
          for (int a = 0; a < 3; ++a)
            for (int side = -1; side <= 1; side += 2) {
              const long j = grid.neighbour(x, y, z, a, side);
              if (j < 0) {  // vacuum beyond: Marshak, flux phi / (h / 2D + 2) through the face
                den += 1.0 / (g.cell_m[a] * (g.cell_m[a] / (2.0 * diff[i]) + 2.0));
              } else {
                const double dj = diff[size_t(j)];
                const double c = 2.0 * diff[i] * dj / ((diff[i] + dj) * h2[a]);
                num += c * phi[size_t(j)];
                den += c;
              }
            }
          const double target = den > 0 ? num / den : 0.0;
          next[i] = std::max(0.0, (1.0 - o.relaxation) * phi[i] + o.relaxation * target);
        }
    });
    phi.swap(next);
  };

  // Convergence: the largest change of an iteration relative to the largest fluence.
  auto largest = [&](const std::vector<double>& a, const std::vector<double>* b) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, cells), 0.0,
        [&](const tbb::blocked_range<size_t>& range, double m) {
          for (size_t i = range.begin(); i < range.end(); ++i)
            m = std::max(m, b ? std::abs(a[i] - (*b)[i]) : std::abs(a[i]));
          return m;
        },
        [](double x, double y) { return std::max(x, y); });
  };
  std::vector<double> before;
  for (r.iterations = 0; r.iterations < o.max_iterations;) {
    before = phi;
    if (r.iterations % kSweepsPerLimiter == 0) update_diffusion();
    half_sweep(0);
    half_sweep(1);
    r.iterations += 1;
    const double top = largest(phi, nullptr);
    r.change = top > 0 ? largest(phi, &before) / top : 0.0;
    if (r.change < o.tolerance) {
      r.converged = true;
      break;
    }
  }
  // Energy balance of the result: what the cells absorb and what leaves through the vacuum faces,
  // against what the source puts in (equal at convergence: the discrete operator conserves it).
  update_diffusion();
  double in = 0, absorbed = 0, leaked = 0;
  const double volume = g.cell_m.x * g.cell_m.y * g.cell_m.z;
  for (int z = 0; z < g.dims.z; ++z)
    for (int y = 0; y < g.dims.y; ++y)
      for (int x = 0; x < g.dims.x; ++x) {
        const size_t i = grid.index(x, y, z);
        in += q[i] * volume;
        absorbed += sigma_a[i] * phi[i] * volume;
        for (int a = 0; a < 3; ++a)
          for (int side = -1; side <= 1; side += 2)
            if (grid.neighbour(x, y, z, a, side) < 0)
              leaked += volume / (g.cell_m[a] * (g.cell_m[a] / (2.0 * diff[i]) + 2.0)) * phi[i];
      }
  r.source_power = in;
  r.absorbed_power = absorbed;
  r.leaked_power = leaked;
  // Fick's law, F = -D grad phi, with the final D (the limiter keeps |F| <= phi): the net flux
  // that makes the diffuse light leaving a surface brighter toward the outside than phi / 4 pi.
  r.flux.assign(cells, glm::dvec3(0.0));
  for (int z = 0; z < g.dims.z; ++z)
    for (int y = 0; y < g.dims.y; ++y)
      for (int x = 0; x < g.dims.x; ++x) {
        const size_t i = grid.index(x, y, z);
        for (int a = 0; a < 3; ++a) {
          const long lo = grid.neighbour(x, y, z, a, -1), hi = grid.neighbour(x, y, z, a, +1);
          const double h = g.cell_m[a];
          // Beyond a face to vacuum: phi falls to 0 over the extrapolation length 2 D (Marshak).
          const double p_lo = lo >= 0 ? phi[size_t(lo)] : phi[i] * (1.0 - 2.0 * h / (h + 4.0 * diff[i]));
          const double p_hi = hi >= 0 ? phi[size_t(hi)] : phi[i] * (1.0 - 2.0 * h / (h + 4.0 * diff[i]));
          r.flux[i][a] = -diff[i] * (p_hi - p_lo) / (2.0 * h);
        }
        const double len = glm::length(r.flux[i]);
        if (len > phi[i] && len > 0) r.flux[i] *= phi[i] / len;
      }
  return r;
}

// The next coarser grid: cells of 2x2x2 (the last one partly outside the box where a count is odd,
// that part empty), extinction and source averaged.
MsDiffusionGrid coarser(const MsDiffusionGrid& g) {
  MsDiffusionGrid c;
  c.dims = (g.dims + 1) / 2;
  c.cell_m = g.cell_m * 2.0;
  c.tiles_xz = g.tiles_xz;
  const size_t cells = size_t(c.dims.x) * size_t(c.dims.y) * size_t(c.dims.z);
  c.sigma_t.assign(cells, 0.0);
  c.source.assign(cells, 0.0);
  for (int z = 0; z < g.dims.z; ++z)
    for (int y = 0; y < g.dims.y; ++y)
      for (int x = 0; x < g.dims.x; ++x) {
        const size_t f = (size_t(z) * g.dims.y + y) * g.dims.x + x;
        const size_t k = (size_t(z / 2) * c.dims.y + y / 2) * c.dims.x + x / 2;
        c.sigma_t[k] += g.sigma_t[f] / 8.0;
        c.source[k] += g.source[f] / 8.0;
      }
  return c;
}

// A coarse solution at the fine cell centres, trilinear (clamped at the box's faces).
std::vector<double> prolong(const std::vector<double>& coarse, glm::ivec3 nc, glm::ivec3 nf) {
  std::vector<double> fine(size_t(nf.x) * size_t(nf.y) * size_t(nf.z));
  auto at = [&](int x, int y, int z) {
    x = std::clamp(x, 0, nc.x - 1), y = std::clamp(y, 0, nc.y - 1), z = std::clamp(z, 0, nc.z - 1);
    return coarse[(size_t(z) * nc.y + y) * nc.x + x];
  };
  for (int z = 0; z < nf.z; ++z)
    for (int y = 0; y < nf.y; ++y)
      for (int x = 0; x < nf.x; ++x) {
        const glm::dvec3 u = (glm::dvec3(x, y, z) + 0.5) / 2.0 - 0.5;
        const glm::dvec3 fl = glm::floor(u), t = u - fl;
        const glm::ivec3 i(fl);
        double v = 0;
        for (int k = 0; k < 8; ++k) {
          const int dx = k & 1, dy = (k >> 1) & 1, dz = k >> 2;
          v += (dx ? t.x : 1 - t.x) * (dy ? t.y : 1 - t.y) * (dz ? t.z : 1 - t.z) * at(i.x + dx, i.y + dy, i.z + dz);
        }
        fine[(size_t(z) * nf.y + y) * nf.x + x] = v;
      }
  return fine;
}

}  // namespace

// Nested iteration: each grid starts from the next coarser one's solution (down to 4 cells on the
// shortest axis), so the slow, large-scale part of the solution is found where it is cheap.
MsDiffusionResult solve_ms_diffusion(const MsDiffusionGrid& g, const MsDiffusionOptions& o) {
  const size_t cells = size_t(g.dims.x) * size_t(g.dims.y) * size_t(g.dims.z);
  if (g.dims.x < 1 || g.dims.y < 1 || g.dims.z < 1 || g.sigma_t.size() != cells || g.source.size() != cells)
    throw std::invalid_argument("solve_ms_diffusion: the grid's arrays do not match its dimensions");
  if (!(g.cell_m.x > 0 && g.cell_m.y > 0 && g.cell_m.z > 0))
    throw std::invalid_argument("solve_ms_diffusion: cell sizes must be positive");
  if (!(o.albedo >= 0 && o.albedo <= 1) || !(o.asymmetry > -1 && o.asymmetry < 1))
    throw std::invalid_argument("solve_ms_diffusion: albedo must be in [0, 1] and the asymmetry in (-1, 1)");
  if (!(o.relaxation > 0 && o.relaxation < 2) || o.max_iterations < 1)
    throw std::invalid_argument("solve_ms_diffusion: the relaxation factor must be in (0, 2) and max_iterations >= 1");
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> initial;
  int coarse_iterations = 0;
  if (std::min({g.dims.x, g.dims.y, g.dims.z}) >= 8) {
    const MsDiffusionGrid c = coarser(g);
    MsDiffusionResult rc = solve_ms_diffusion(c, o);
    initial = prolong(rc.fluence, c.dims, g.dims);
    coarse_iterations = rc.iterations + rc.coarse_iterations;
  }
  MsDiffusionResult r = iterate(g, o, std::move(initial));
  r.coarse_iterations = coarse_iterations;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

std::vector<glm::dvec4> ms_volume_texels(const MsDiffusionResult& solve, double asymmetry) {
  std::vector<glm::dvec4> t(solve.fluence.size());
  for (size_t i = 0; i < t.size(); ++i)
    t[i] = glm::dvec4(solve.fluence[i], 3.0 * asymmetry * (i < solve.flux.size() ? solve.flux[i] : glm::dvec3(0.0)));
  return t;
}

}  // namespace cloudviewer
