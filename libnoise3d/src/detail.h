// Internal helpers shared by the point and batch paths of libnoise3d.
#pragma once

#include <cmath>
#include <cstdint>

#include "noise3d/noise3d.h"

namespace noise3d::detail {

// Murmur3's 32-bit finaliser: a bijection with full avalanche. Unsigned arithmetic only, so it
// wraps identically in C++ and GLSL and vectorises (32-bit multiplies) on AVX2/AVX-512.
inline uint32_t fmix32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

/// 64-bit seed plus a salt (octave, noise kind, curl component) folded to a 32-bit key.
inline uint32_t seed_key(uint64_t seed, uint32_t salt) {
  uint32_t lo = static_cast<uint32_t>(seed), hi = static_cast<uint32_t>(seed >> 32);
  return fmix32(lo ^ fmix32(hi ^ fmix32(salt * 0x9e3779b9u + 0x7f4a7c15u)));
}

// Lattice hash in two stages, so a row of x lattice points with fixed (y, z) costs one fmix each:
//   row = fmix(fmix(z*K3 + key) ^ y*K2),  h = fmix(row ^ x*K1)
// x, y, z are lattice indices already wrapped into [0, period).
inline uint32_t hash_row(uint32_t y, uint32_t z, uint32_t key) {
  return fmix32(fmix32(z * 0xcb1ab31fu + key) ^ (y * 0xd8163841u));
}
inline uint32_t hash_x(uint32_t row, uint32_t x) { return fmix32(row ^ (x * 0x8da6b343u)); }
inline uint32_t hash3(uint32_t x, uint32_t y, uint32_t z, uint32_t key) {
  return hash_x(hash_row(y, z, key), x);
}

/// One of Perlin's 12 edge gradients (+-1,+-1,0), (+-1,0,+-1), (0,+-1,+-1), chosen uniformly
/// (multiply-high maps the 32-bit hash onto 0..11 without modulo bias worth measuring).
inline uint32_t grad_index(uint32_t h) {
  return static_cast<uint32_t>((static_cast<uint64_t>(h) * 12u) >> 32);
}
inline constexpr float kGradX[12] = {1, -1, 1, -1, 1, -1, 1, -1, 0, 0, 0, 0};
inline constexpr float kGradY[12] = {1, 1, -1, -1, 0, 0, 0, 0, 1, -1, 1, -1};
inline constexpr float kGradZ[12] = {0, 0, 0, 0, 1, 1, -1, -1, 1, 1, -1, -1};

/// Worley feature-point jitter on one axis from a cell hash, uniform in [0, 1) with 24 bits.
inline uint32_t jitter_hash(uint32_t h, uint32_t axis) {
  return axis == 0 ? h : fmix32(h + axis * 0x68e31da4u);
}
template <class T>
inline T jitter01(uint32_t h) {
  return static_cast<T>(h >> 8) * static_cast<T>(1.0 / 16777216.0);
}

/// Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative 30t^2(t-1)^2.
template <class T>
inline T fade(T t) {
  return t * t * t * (t * (t * T(6) - T(15)) + T(10));
}
template <class T>
inline T dfade(T t) {
  return T(30) * t * t * (t * (t - T(2)) + T(1));
}

/// Wraps an unwrapped lattice index into [0, period).
inline uint32_t wrap(int64_t i, uint32_t period) {
  int64_t m = i % static_cast<int64_t>(period);
  return static_cast<uint32_t>(m < 0 ? m + period : m);
}

/// Splits a coordinate into an integer cell and a fraction in [0, 1). Throws on NaN/inf.
struct Split {
  int64_t cell;
  double frac;
};
Split split(double x, const char* axis);
void check_period(Period p, const char* name = "period");

}  // namespace noise3d::detail
