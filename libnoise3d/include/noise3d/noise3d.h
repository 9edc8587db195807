// libnoise3d: tileable 3D noise for baking cloud volumes.
//
// Improved Perlin noise (Perlin 2002, "Improving Noise", quintic fade, 12 edge gradients),
// cellular / Worley noise (Worley 1996, one feature point per cell, exact F1 and F2),
// fBm of either, Horizon-Zero-Dawn style Perlin-Worley, and curl noise (Bridson 2007) built from
// analytic Perlin derivatives.
//
// Conventions
//  - Coordinates are in lattice units of the base octave: one lattice cell is one unit, and a
//    function with period P repeats every P units on that axis: f(p) == f(p + k*P) for integer k.
//  - Periods are any positive integer per axis (1 .. kMaxPeriod), not only powers of two.
//  - Everything is a pure function of (parameters, seed, position): results do not depend on the
//    thread count or on the order in which points are evaluated.
//  - Lattice arithmetic is done on 64-bit integers and hashed with unsigned 32-bit integer hashes
//    (no sin()-hash, no signed overflow), so large coordinates and periods keep the wrap.
//  - Invalid parameters throw noise3d::InvalidParameter naming the parameter and the allowed range.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace noise3d {

/// Base class of every error the library throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A parameter is outside its allowed range. `parameter()` is its name ("period.x", "octaves"...).
class InvalidParameter : public Error {
 public:
  InvalidParameter(std::string parameter, const std::string& message)
      : Error(parameter + ": " + message), parameter_(std::move(parameter)) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

/// Largest absolute value improved Perlin noise with Perlin's 12 edge gradients can return in 3D
/// (the often-quoted 0.866 = sqrt(3)/2 is wrong for this gradient set). `perlin()` returns raw
/// values in [-kPerlinBound, kPerlinBound]; fBm divides by it so its range is [-1, 1].
inline constexpr double kPerlinBound = 1.0363538;
/// Largest possible F1 of the inverted Worley form: the diagonal of one cell.
inline constexpr double kSqrt3 = 1.7320508075688772;
inline constexpr uint32_t kMaxPeriod = 1u << 30;
inline constexpr int kMaxOctaves = 16;
inline constexpr int kMaxLacunarity = 16;

struct Period {
  uint32_t x = 1, y = 1, z = 1;
  static Period cube(uint32_t p) { return {p, p, p}; }
};

// ---------------------------------------------------------------------------------------------
// Single-octave primitives. Position in lattice units; `seed` selects an independent pattern.
// They validate their arguments (finite coordinates, period in [1, kMaxPeriod]).

/// Improved Perlin noise, tileable with `period`. Returns a value in [-kPerlinBound, kPerlinBound];
/// 0 at every lattice point. The lattice split is done in double, the interpolation in float.
float perlin(double x, double y, double z, Period period, uint64_t seed);
/// Same in double precision throughout.
double perlin_d(double x, double y, double z, Period period, uint64_t seed);

/// Perlin value and its analytic gradient (d/dx, d/dy, d/dz), double precision.
struct ValueGrad {
  double value;
  std::array<double, 3> grad;
};
ValueGrad perlin_grad(double x, double y, double z, Period period, uint64_t seed);

/// Exact distances to the nearest (F1) and second-nearest (F2) feature point, one feature point per
/// cell jittered uniformly and independently on each axis over the whole cell. Exact: the 3x3x3
/// neighbourhood is searched first, then further rings of cells are searched while a cell's box can
/// still hold a closer point (pruned by box distance), so rare configurations that a plain 3x3x3
/// search gets wrong are handled. F1 <= sqrt(3) always (the point of the own cell is in the cell).
struct WorleyF {
  double f1, f2;
};
WorleyF worley(double x, double y, double z, Period period, uint64_t seed);
/// Inverted Worley as in the thesis: 1 - F1/sqrt(3), in [0, 1]; 1 at feature points.
float worley_inverted(double x, double y, double z, Period period, uint64_t seed);

/// Curl of a vector potential made of three independent Perlin noises (seeds derived from `seed`),
/// computed from analytic derivatives: divergence-free, tileable with `period`. Each component is
/// bounded by 2 * kPerlinBound * 30/16 (two gradient terms of magnitude at most the Perlin
/// derivative bound); typical magnitudes are around 1.
std::array<double, 3> curl(double x, double y, double z, Period period, uint64_t seed);

/// Ken Perlin's published reference `ImprovedNoise.noise(x, y, z)` (Java, 2002): his permutation
/// table, period 256, double precision, no seed. Used to check our implementation of the algorithm.
double perlin_reference(double x, double y, double z);

// ---------------------------------------------------------------------------------------------
// Fractal noise: the thing cloudgen bakes.

enum class Kind { Perlin, Worley, PerlinWorley };
const char* kind_name(Kind k);
/// Parses "perlin", "worley", "perlin-worley"; throws InvalidParameter("kind", ...) otherwise.
Kind parse_kind(const std::string& s);

struct FractalParams {
  Kind kind = Kind::Perlin;
  Period period = Period::cube(4);  ///< base-octave period in lattice cells, each in [1, kMaxPeriod]
  uint64_t seed = 0;
  int octaves = 1;                  ///< [1, kMaxOctaves]
  double gain = 0.5;                ///< amplitude ratio between octaves, in (0, 1]
  /// Frequency ratio between octaves. Must be an integer in [2, kMaxLacunarity]: octave o has period
  /// period * lacunarity^o, which stays an integer so the sum still tiles. A non-integer is rejected.
  double lacunarity = 2.0;
  /// Perlin-Worley only: number of Worley octaves (0 = same as `octaves`).
  int worley_octaves = 0;
  /// Perlin-Worley only, in [0, 1]: 1 = the full Perlin-Worley remap, 0 = the Perlin fBm alone
  /// (mapped to [0, 1]); in between, value = p + blend * (pw - p).
  double blend = 1.0;
};

/// Throws InvalidParameter naming the first bad field (and the allowed range).
void validate(const FractalParams& p);

/// Value ranges (documented contract, checked by the tests):
///  - Perlin fBm:  sum_o gain^o * perlin_o / (kPerlinBound * sum_o gain^o), in [-1, 1]
///  - Worley fBm:  sum_o gain^o * worley_inverted_o / sum_o gain^o,          in [0, 1]
///  - Perlin-Worley (Hillaire's TileableVolumeNoise remap of Schneider's Nubis base shape):
///      p = clamp(0.5 + 0.5 * perlin_fbm, 0, 1); w = worley_fbm; pw = w + p * (1 - w), in [0, 1];
///      value = pw when blend = 1 (default), else p + blend * (pw - p)
///    Perlin dilated by Worley: billowy Perlin blobs with Worley's round, connected cells.
/// Each octave uses its own seed derived from `seed` and the octave index.
double evaluate(const FractalParams& p, double x, double y, double z);
/// Theoretical output range of evaluate() for these params ({-1,1} or {0,1}).
std::array<double, 2> value_range(Kind k);

// ---------------------------------------------------------------------------------------------
// Batch evaluation over a grid that spans exactly one tile.

/// A tile sampled with size.{x,y,z} samples per axis: sample (i, j, k) sits at lattice position
/// (i * period.x / size.x, j * period.y / size.y, k * period.z / size.z), computed exactly in
/// integers. So the cube is one tile: copies laid side by side are seamless. `origin`/`extent`
/// select a sub-box (default: the whole tile); a sub-box gives exactly the values of the same
/// samples in the whole tile.
struct GridRegion {
  std::array<uint32_t, 3> size{{32, 32, 32}};
  std::array<uint32_t, 3> origin{{0, 0, 0}};
  std::array<uint32_t, 3> extent{{0, 0, 0}};  ///< 0 on an axis = size - origin
  static GridRegion whole(uint32_t n) { return GridRegion{{{n, n, n}}, {{0, 0, 0}}, {{0, 0, 0}}}; }
  std::array<uint32_t, 3> resolved_extent() const;
  size_t count() const;
};

struct BatchOptions {
  int threads = 0;  ///< 0 = all cores (TBB default); results are identical for any value
};

struct MinMax {
  double min, max;
};

/// Evaluates `evaluate(p, position(i,j,k))` for every sample of `region` into the caller-owned
/// buffer `out` of region.count() values, in memory order x fastest, then y, then z:
///   out[(k * extent.y + j) * extent.x + i]
/// Matches the point function within 1e-6 (float) / 1e-12 (double). Returns min and max.
MinMax evaluate_grid(const FractalParams& p, const GridRegion& region, float* out,
                     const BatchOptions& opt = {});
MinMax evaluate_grid(const FractalParams& p, const GridRegion& region, double* out,
                     const BatchOptions& opt = {});

/// Library version string, e.g. "0.1.0".
const char* version();

}  // namespace noise3d
