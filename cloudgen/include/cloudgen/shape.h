// Shape sources: analytic primitives (ellipsoid, sphere, capsule) that say where a cloud is. Their
// smooth union is a signed distance d in metres (negative inside), and the cloud's noise-free base
// density is a smoothstep falloff of d:
//
//     s(d) = S(clamp(0.5 - d / falloff, 0, 1)),   S(u) = u^2 (3 - 2 u)
//
// so s = 1 for d <= -falloff/2, s = 0.5 on the surface, s = 0 for d >= falloff/2. The noise then
// erodes it as without shapes: density = clamp(density_scale * (R * s - t) / (1 - t), 0, 1).
//
// Frame: the preset's world frame in metres, y up (the frame of `origin` and `view.eye`). Voxel
// (i, j, k) has its centre at origin + (i + 0.5, j + 0.5, k + 0.5) * voxel_size.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cloudgen {

struct TriangleMesh;
struct VdbShape;
class MeshDistance;

using ShapeVec = std::array<double, 3>;

enum class ShapeKind { Ellipsoid, Sphere, Capsule, Mesh, Vdb };
const char* shape_kind_name(ShapeKind k);

/// One source as the preset writes it. Placement: scale (in the source's own axes) and rotate
/// (degrees about x, then y, then z) about the source's centre (a capsule's: the middle of a-b),
/// then translate. A mesh's centre is the middle of its bounding box, and `fit` first scales it
/// evenly and moves it so it fills the volume (fit_sources).
struct ShapeSource {
  std::optional<ShapeKind> kind;
  std::optional<ShapeVec> center, radii, a, b;  ///< ellipsoid: center, radii; sphere: center; capsule: a, b
  std::optional<double> radius;                  ///< sphere, capsule
  std::optional<std::string> file;               ///< mesh, vdb: the file as written in the preset
  bool fit = false;                              ///< mesh, vdb: fit into the volume (fit_sources)
  std::optional<std::string> grid, up;           ///< vdb: the grid's name; the file's up axis ("y", "z")
  std::optional<double> iso;                     ///< vdb: a fog volume's density at the surface
  ShapeVec translate{{0, 0, 0}}, rotate{{0, 0, 0}}, scale{{1, 1, 1}};
  std::shared_ptr<const TriangleMesh> mesh;  ///< mesh: read by the preset's reader (mesh_source.h)
  std::shared_ptr<const VdbShape> vdb;       ///< vdb: read by the preset's reader (mesh_source.h)
  double fit_scale = 1;                      ///< set by fit_sources: an even scale before `scale`
  ShapeVec fit_offset{{0, 0, 0}};            ///< set by fit_sources: a move before `translate`
};

/// A noise modifier of the signed distance (docs/shaping.md, "Billowy and wispy"): off while its
/// amplitude is 0. The noise is in world metres (first octave `period` metres, each next one half
/// the size and `gain` times the weight), seeded from the preset's seed. Its weight w in [0, 1] is
/// the product of a height ramp, a depth mask and (wispy) a downwind mask:
///   billowy (cauliflower): d' = d - amplitude * w * B(p), B in [0, 1] an fBm of Worley domes
///     cells: the surface moves out along the distance's gradient by up to `amplitude`;
///   wispy (erosion): d' = d + amplitude * w * E(p), E in [0, 1] an fBm of Perlin noise whose
///     lookup is advected along curl noise (`warp` periods): the surface is eaten into fibres.
struct ShapeModifier {
  double amplitude = 0;  ///< metres; 0 = off
  double period = 400;   ///< metres: the first octave's cell or wavelength
  int octaves = 3;       ///< 1 .. 8, each twice as fine
  double gain = 0.6;     ///< weight of each octave against the previous one
  /// World heights (metres, y) of the ramp: w_h = 0 at heights[0], 1 at heights[1], smooth in
  /// between and constant beyond (heights[0] > heights[1]: stronger low down). Unset: 1.
  std::optional<std::array<double, 2>> heights;
  double depth = 300;    ///< metres below the surface (d < 0) over which w falls from 1 to 0
  double warp = 0.5;     ///< wispy: curl advection of the noise lookup, in periods
  ShapeVec wind{{1, 0, 0}};  ///< wispy: the direction it blows to (need not be unit)
  double downwind = 0.5;     ///< wispy: 0 = all round, 1 = only on the downwind side
  bool on() const { return amplitude > 0; }
};

/// The preset's `shape` section. No sources: the height profile, towers and coverage place the
/// cloud as before (and the bytes are those of a preset without the section).
struct ShapeParams {
  double blend = 0;      ///< metres of the smooth union (polynomial smooth-min); 0 = hard union
  double falloff = 100;  ///< metres from s = 1 to s = 0 across the surface
  /// World heights (metres, y) that cut the union flat: d = max(d, floor - y, y - ceiling). A
  /// cumulus base at the condensation level, an anvil under the tropopause.
  std::optional<double> floor, ceiling;
  std::vector<ShapeSource> sources;
  ShapeModifier billowy, wispy;
};

/// At most this many sources (each costs every voxel near the shape an evaluation).
inline constexpr size_t kMaxShapeSources = 64;
/// At most this many of them meshes or VDB grids (each holds a distance lattice, mesh_source.h).
inline constexpr size_t kMaxMeshSources = 8;

/// The problems of a shape section ("<pointer>", "<what>"), empty when it can be placed: at most
/// kMaxShapeSources sources, each with its kind's keys and no other kind's; a capsule's scale is
/// uniform.
std::vector<std::pair<std::string, std::string>> shape_problems(const ShapeParams& s);

/// Sets fit_scale and fit_offset of every source with `fit`: the placed mesh's box (after scale and
/// rotate) scaled evenly and centred so it fills the volume less falloff / 2 + billowy.amplitude +
/// one voxel on each side; `translate` then moves it from there.
void fit_sources(ShapeParams& s, const ShapeVec& origin, const std::array<uint32_t, 3>& n, double voxel_size);

/// The sources placed in the world, ready to evaluate. Thread-safe to read.
class ShapeField {
 public:
  /// s must have no shape_problems and its meshes read; a mesh's distance is sampled every
  /// `voxel_size` metres (coarser when the mesh's box would need more than kMaxMeshSamples). `seed`
  /// seeds the billowy and wispy noise (the preset's seed).
  explicit ShapeField(const ShapeParams& s, double voxel_size = 0, uint64_t seed = 0);
  bool empty() const { return prims_.empty(); }

  /// The signed distance d at p: the smooth union of the sources in their order, cut by the
  /// floor and the ceiling (no modifiers).
  double distance(const ShapeVec& p) const;
  /// The union's distance with the billowy and wispy modifiers, then the cuts (which stay flat): in
  /// [d - billowy.amplitude, d + wispy.amplitude].
  double modified_distance(const ShapeVec& p) const;
  /// The base density s(d') at p, in [0, 1]; the modifiers' noise is evaluated only where s can
  /// differ from 0 and 1 (the bounds above decide, in the same floating-point expressions).
  double density(const ShapeVec& p) const;
  /// Whether s is 0 at every point within `radius` of `c` (a conservative proof: a lower bound of d
  /// over the ball, with a margin for rounding, reaches falloff / 2).
  bool zero_in_ball(const ShapeVec& c, double radius) const;
  /// The centre of a voxel with s > 0 in the layers at the x and z faces of a volume of n voxels
  /// of `voxel_size` from `origin` (a tiling volume wraps there and shapes do not), or none.
  std::optional<ShapeVec> nonzero_at_side_faces(const ShapeVec& origin, const std::array<uint32_t, 3>& n,
                                                 double voxel_size) const;

  /// A box (min, max corners) outside which s is 0: conservative, loose for long ellipsoids.
  std::array<ShapeVec, 2> support_box() const;

  struct Prim {
    std::shared_ptr<const MeshDistance> mesh;  ///< a mesh (then nothing below is used)
    bool capsule;        ///< else an ellipsoid
    ShapeVec c, radii;   ///< ellipsoid: centre and radii along its own axes
    double rot[3][3];    ///< ellipsoid: columns are its axes in the world
    ShapeVec a, b;       ///< capsule: the segment (a == b: a sphere)
    double r;            ///< capsule radius; ellipsoid: its smallest radius
  };

 private:
  double blend_, falloff_;
  std::optional<double> floor_, ceiling_;
  ShapeModifier billowy_, wispy_;
  uint64_t seed_;
  double step_;  ///< the gradient's central-difference step (wispy's downwind mask)
  double union_distance(const ShapeVec& p) const;       ///< the smooth union, no cuts
  double cut(const ShapeVec& p, double d) const;        ///< d cut by the floor and the ceiling
  double modify(const ShapeVec& p, double d) const;     ///< the modifiers applied to the union's d
  std::vector<Prim> prims_;
};

/// s(d) = S(clamp(0.5 - d / falloff, 0, 1)).
double shape_falloff(double d, double falloff);
/// Polynomial smooth minimum (Inigo Quilez): min(a, b) - h^2 k / 4, h = max(k - |a - b|, 0) / k.
/// Never below min(a, b) - k / 4, non-decreasing in a and in b; k = 0 is min.
double smooth_min(double a, double b, double k);

}  // namespace cloudgen
