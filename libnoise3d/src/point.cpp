// Point evaluation of every noise kind: the readable definition. The batch path in grid.cpp is the
// fast one and is tested against these functions.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "detail.h"
#include "noise3d/noise3d.h"

namespace noise3d {
namespace detail {

Split split(double x, const char* axis) {
  if (!std::isfinite(x))
    throw InvalidParameter(std::string("coordinate.") + axis, "must be finite, got " + std::to_string(x));
  // 2^62: beyond it a double has no fractional bits left and the cell index would overflow int64.
  if (std::fabs(x) > 4.6e18)
    throw InvalidParameter(std::string("coordinate.") + axis, "magnitude must be below 4.6e18");
  double f = std::floor(x);
  return {static_cast<int64_t>(f), x - f};
}

void check_period(Period p, const char* name) {
  const uint32_t v[3] = {p.x, p.y, p.z};
  const char* ax[3] = {".x", ".y", ".z"};
  for (int a = 0; a < 3; ++a)
    if (v[a] < 1 || v[a] > kMaxPeriod)
      throw InvalidParameter(std::string(name) + ax[a], "must be an integer in [1, " +
                                                            std::to_string(kMaxPeriod) + "], got " +
                                                            std::to_string(v[a]));
}

}  // namespace detail

using namespace detail;

namespace {

struct Lattice {
  uint32_t x0, x1, y0, y1, z0, z1;
  double fx, fy, fz;
};

Lattice lattice(double x, double y, double z, Period p) {
  check_period(p);
  Split sx = split(x, "x"), sy = split(y, "y"), sz = split(z, "z");
  Lattice l;
  l.x0 = wrap(sx.cell, p.x), l.x1 = wrap(sx.cell + 1, p.x);
  l.y0 = wrap(sy.cell, p.y), l.y1 = wrap(sy.cell + 1, p.y);
  l.z0 = wrap(sz.cell, p.z), l.z1 = wrap(sz.cell + 1, p.z);
  l.fx = sx.frac, l.fy = sy.frac, l.fz = sz.frac;
  return l;
}

template <class T>
T grad_dot(uint32_t h, T x, T y, T z) {
  uint32_t g = grad_index(h);
  return T(kGradX[g]) * x + T(kGradY[g]) * y + T(kGradZ[g]) * z;
}

template <class T>
T perlin_t(double x, double y, double z, Period p, uint64_t seed) {
  Lattice l = lattice(x, y, z, p);
  uint32_t key = seed_key(seed, 0x9e11u);
  T fx = T(l.fx), fy = T(l.fy), fz = T(l.fz);
  T u = fade(fx), v = fade(fy), w = fade(fz);
  auto n = [&](uint32_t xi, uint32_t yi, uint32_t zi, T dx, T dy, T dz) {
    return grad_dot<T>(hash3(xi, yi, zi, key), dx, dy, dz);
  };
  auto lerp = [](T t, T a, T b) { return a + t * (b - a); };
  T x00 = lerp(u, n(l.x0, l.y0, l.z0, fx, fy, fz), n(l.x1, l.y0, l.z0, fx - 1, fy, fz));
  T x10 = lerp(u, n(l.x0, l.y1, l.z0, fx, fy - 1, fz), n(l.x1, l.y1, l.z0, fx - 1, fy - 1, fz));
  T x01 = lerp(u, n(l.x0, l.y0, l.z1, fx, fy, fz - 1), n(l.x1, l.y0, l.z1, fx - 1, fy, fz - 1));
  T x11 = lerp(u, n(l.x0, l.y1, l.z1, fx, fy - 1, fz - 1), n(l.x1, l.y1, l.z1, fx - 1, fy - 1, fz - 1));
  return lerp(w, lerp(v, x00, x10), lerp(v, x01, x11));
}

}  // namespace

float perlin(double x, double y, double z, Period p, uint64_t seed) {
  return perlin_t<float>(x, y, z, p, seed);
}
double perlin_d(double x, double y, double z, Period p, uint64_t seed) {
  return perlin_t<double>(x, y, z, p, seed);
}

ValueGrad perlin_grad(double x, double y, double z, Period p, uint64_t seed) {
  Lattice l = lattice(x, y, z, p);
  uint32_t key = seed_key(seed, 0x9e11u);
  const double f[3] = {l.fx, l.fy, l.fz};
  const double s[3] = {fade(f[0]), fade(f[1]), fade(f[2])};
  const double ds[3] = {dfade(f[0]), dfade(f[1]), dfade(f[2])};
  const uint32_t xi[2] = {l.x0, l.x1}, yi[2] = {l.y0, l.y1}, zi[2] = {l.z0, l.z1};
  ValueGrad r{0, {0, 0, 0}};
  // noise = sum over corners c of W_c(p) * n_c(p), W_c = prod of (s or 1-s), n_c = g_c . (p - c).
  for (int c = 0; c < 8; ++c) {
    const int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    uint32_t g = grad_index(hash3(xi[b[0]], yi[b[1]], zi[b[2]], key));
    const double gv[3] = {kGradX[g], kGradY[g], kGradZ[g]};
    double d[3], w[3], dw[3];
    for (int a = 0; a < 3; ++a) {
      d[a] = f[a] - b[a];
      w[a] = b[a] ? s[a] : 1 - s[a];
      dw[a] = b[a] ? ds[a] : -ds[a];
    }
    double n = gv[0] * d[0] + gv[1] * d[1] + gv[2] * d[2];
    double W = w[0] * w[1] * w[2];
    r.value += W * n;
    r.grad[0] += dw[0] * w[1] * w[2] * n + W * gv[0];
    r.grad[1] += w[0] * dw[1] * w[2] * n + W * gv[1];
    r.grad[2] += w[0] * w[1] * dw[2] * n + W * gv[2];
  }
  return r;
}

namespace {

// Feature point of the (unwrapped) cell c, relative to the cell's corner, jitter in [0,1)^3.
struct Feature {
  double jx, jy, jz;
};
Feature feature(int64_t cx, int64_t cy, int64_t cz, Period p, uint32_t key) {
  uint32_t h = hash3(wrap(cx, p.x), wrap(cy, p.y), wrap(cz, p.z), key);
  return {jitter01<double>(jitter_hash(h, 0)), jitter01<double>(jitter_hash(h, 1)),
          jitter01<double>(jitter_hash(h, 2))};
}

}  // namespace

WorleyF worley(double x, double y, double z, Period p, uint64_t seed) {
  check_period(p);
  Split sx = split(x, "x"), sy = split(y, "y"), sz = split(z, "z");
  uint32_t key = seed_key(seed, 0x3a71u);
  double f1 = std::numeric_limits<double>::infinity(), f2 = f1;  // squared distances
  const double fr[3] = {sx.frac, sy.frac, sz.frac};
  // Rings of cells at Chebyshev distance r around the sample's cell. Any point in a cell of ring r
  // is at least (r - 1) + min(frac, 1 - frac) away along the axis where the cell is r away, so
  // the search stops once that bound reaches F2 (F1 <= sqrt(3) and F2 <= sqrt(6) < 3 cap r at 3).
  for (int r = 0;; ++r) {
    for (int dz = -r; dz <= r; ++dz)
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
          // Box distance from the sample to this cell: prune cells that cannot beat F2.
          const int d[3] = {dx, dy, dz};
          double box = 0;
          for (int a = 0; a < 3; ++a) {
            double g = d[a] > 0 ? d[a] - fr[a] : d[a] < 0 ? fr[a] - (d[a] + 1) : 0.0;
            box += g * g;
          }
          if (box >= f2) continue;
          Feature ft = feature(sx.cell + dx, sy.cell + dy, sz.cell + dz, p, key);
          double ex = dx + ft.jx - fr[0], ey = dy + ft.jy - fr[1], ez = dz + ft.jz - fr[2];
          double d2 = ex * ex + ey * ey + ez * ez;
          if (d2 < f1) {
            f2 = f1;
            f1 = d2;
          } else if (d2 < f2) {
            f2 = d2;
          }
        }
    // Smallest possible distance to any cell of ring r+1.
    double next = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) next = std::min(next, r + std::min(fr[a], 1 - fr[a]));
    if (next * next >= f2) break;
  }
  return {std::sqrt(f1), std::sqrt(f2)};
}

float worley_inverted(double x, double y, double z, Period p, uint64_t seed) {
  return static_cast<float>(1.0 - worley(x, y, z, p, seed).f1 / kSqrt3);
}

std::array<double, 3> curl(double x, double y, double z, Period p, uint64_t seed) {
  // Vector potential psi = (N1, N2, N3), three independent Perlin noises; v = curl psi.
  ValueGrad a = perlin_grad(x, y, z, p, seed_key(seed, 0xc011u));
  ValueGrad b = perlin_grad(x, y, z, p, seed_key(seed, 0xc012u));
  ValueGrad c = perlin_grad(x, y, z, p, seed_key(seed, 0xc013u));
  return {c.grad[1] - b.grad[2], a.grad[2] - c.grad[0], b.grad[0] - a.grad[1]};
}

}  // namespace noise3d
