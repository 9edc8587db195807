// Shape sources placed in the world and their smooth union (shape.h).
//
// Distances: a capsule's (and an evenly scaled sphere's, a capsule with a == b) is the exact
// Euclidean distance. An ellipsoid's is Inigo Quilez's approximation d = k0 (k0 - 1) / k1 with
// k0 = |q / r|, k1 = |q / r^2| (q in the ellipsoid's axes): 0 exactly on the surface, exact for a
// sphere. Its lower bound L = rmin (k0 - 1) is 1-Lipschitz (|grad k0| = k1 / k0 <= 1 / rmin), and
// where L > 0, d = L * (k0 / k1) / rmin >= L because k0 / k1 >= rmin. So over a ball of radius h
// around c every source's d is at least L(c) - h (capsules: d(c) - h), and because the smooth
// minimum is non-decreasing in both arguments the same fold over those bounds bounds the union.
// A mesh's distance is sampled on a lattice (mesh_source.h) and its bound over a ball is the least
// sample the ball's box interpolates from.
#include "cloudgen/shape.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cloudgen/mesh_source.h"
#include "cloudgen/schema.h"
#include "noise3d/noise3d.h"

namespace cloudgen {
namespace {

using V = ShapeVec;

V sub(const V& a, const V& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double len(const V& a) { return std::sqrt(dot(a, a)); }

/// R = Rz * Ry * Rx (degrees): about x first, then y, then z, on fixed axes.
void rotation(const V& deg, double R[3][3]) {
  const double k = 3.14159265358979323846 / 180.0;
  const double cx = std::cos(deg[0] * k), sx = std::sin(deg[0] * k), cy = std::cos(deg[1] * k), sy = std::sin(deg[1] * k),
               cz = std::cos(deg[2] * k), sz = std::sin(deg[2] * k);
  const double r[3][3] = {{cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx},
                          {sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx},
                          {-sy, cy * sx, cy * cx}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R[i][j] = r[i][j];
}

/// m + t + R (s * (q - m)): a point of the source placed in the world.
V place(const V& q, const V& m, const ShapeSource& s, const double R[3][3]) {
  V l;
  for (int i = 0; i < 3; ++i) l[i] = s.scale[i] * (q[i] - m[i]);
  V w;
  for (int i = 0; i < 3; ++i) w[i] = m[i] + s.translate[i] + R[i][0] * l[0] + R[i][1] * l[1] + R[i][2] * l[2];
  return w;
}

bool uniform(const V& s) { return s[0] == s[1] && s[1] == s[2]; }

ShapeField::Prim capsule(const V& a, const V& b, double r) {
  ShapeField::Prim p{};
  p.capsule = true, p.a = a, p.b = b, p.r = r;
  return p;
}

ShapeField::Prim ellipsoid(const V& c, const V& radii, const double R[3][3]) {
  ShapeField::Prim p{};
  p.capsule = false, p.c = c, p.radii = radii;
  p.r = std::min({radii[0], radii[1], radii[2]});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p.rot[i][j] = R[i][j];
  return p;
}

/// A mesh's or a VDB grid's own box (its file's frame, y up).
std::array<V, 2> own_box(const ShapeSource& s) {
  if (s.vdb) return {s.vdb->lo, s.vdb->hi};
  return {s.mesh->lo, s.mesh->hi};
}
/// Its centre: the middle of that box.
V mesh_centre(const ShapeSource& s) {
  const auto b = own_box(s);
  return {(b[0][0] + b[1][0]) / 2, (b[0][1] + b[1][1]) / 2, (b[0][2] + b[1][2]) / 2};
}

/// The box of R (k * (corner - m)) over the own box's corners, k = scale * fit_scale per axis.
std::array<V, 2> turned_box(const ShapeSource& s, const double R[3][3], double fit_scale) {
  const auto m = own_box(s);
  const V c = mesh_centre(s);
  std::array<V, 2> b{{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}}};
  for (int corner = 0; corner < 8; ++corner) {
    V l;
    for (int i = 0; i < 3; ++i) l[i] = s.scale[i] * fit_scale * (((corner >> i) & 1 ? m[1][i] : m[0][i]) - c[i]);
    for (int i = 0; i < 3; ++i) {
      const double w = R[i][0] * l[0] + R[i][1] * l[1] + R[i][2] * l[2];
      b[0][i] = std::min(b[0][i], w), b[1][i] = std::max(b[1][i], w);
    }
  }
  return b;
}

ShapeField::Prim resolve(const ShapeSource& s, double voxel_size, double band) {
  double R[3][3];
  rotation(s.rotate, R);
  if (*s.kind == ShapeKind::Mesh || *s.kind == ShapeKind::Vdb) {
    if (!s.mesh && !s.vdb) throw std::logic_error("ShapeField: a mesh or vdb source whose file was not read");
    if (!(voxel_size > 0)) throw std::logic_error("ShapeField: a mesh or vdb source needs the voxel size");
    const V c = mesh_centre(s);
    // world = c + fit_offset + translate + R (k (q - c)): T = [R k | t] as 3 rows of 4.
    std::array<double, 12> T{};
    for (int i = 0; i < 3; ++i) {
      double t = c[i] + s.fit_offset[i] + s.translate[i];
      for (int j = 0; j < 3; ++j) {
        const double a = R[i][j] * s.scale[j] * s.fit_scale;
        T[4 * i + j] = a;
        t -= a * c[j];
      }
      T[4 * i + 3] = t;
    }
    // The lattice's spacing: the voxel size, or coarser so the mesh's box (grown by the band) keeps
    // within kMaxMeshSamples.
    const std::array<V, 2> b = turned_box(s, R, s.fit_scale);
    double h = voxel_size;
    for (int it = 0; it < 64; ++it) {
      double count = 1;
      for (int i = 0; i < 3; ++i) count *= std::ceil((b[1][i] - b[0][i] + 2 * (std::ceil(band / h) + 3) * h) / h) + 1;
      if (count <= 0.9 * double(kMaxMeshSamples)) break;
      h *= 1.1;
    }
    ShapeField::Prim p{};
    p.mesh = s.vdb ? std::make_shared<const MeshDistance>(*s.vdb, T, h, band)
                   : std::make_shared<const MeshDistance>(*s.mesh, T, h, band);
    return p;
  }
  if (*s.kind == ShapeKind::Capsule) {
    const V m{(s.a->at(0) + s.b->at(0)) / 2, (s.a->at(1) + s.b->at(1)) / 2, (s.a->at(2) + s.b->at(2)) / 2};
    return capsule(place(*s.a, m, s, R), place(*s.b, m, s, R), *s.radius * s.scale[0]);
  }
  const V c = place(*s.center, *s.center, s, R);
  if (*s.kind == ShapeKind::Sphere && uniform(s.scale)) return capsule(c, c, *s.radius * s.scale[0]);
  const V r0 = s.kind == ShapeKind::Sphere ? V{*s.radius, *s.radius, *s.radius} : *s.radii;
  return ellipsoid(c, {r0[0] * s.scale[0], r0[1] * s.scale[1], r0[2] * s.scale[2]}, R);
}

/// p in the ellipsoid's own axes, divided by its radii (u = q / r).
V ellipsoid_u(const ShapeField::Prim& e, const V& p) {
  const V d = sub(p, e.c);
  V u;
  for (int j = 0; j < 3; ++j) u[j] = (e.rot[0][j] * d[0] + e.rot[1][j] * d[1] + e.rot[2][j] * d[2]) / e.radii[j];
  return u;
}

double prim_distance(const ShapeField::Prim& e, const V& p) {
  if (e.mesh) return e.mesh->distance(p);
  if (e.capsule) {
    const V pa = sub(p, e.a), ba = sub(e.b, e.a);
    const double bb = dot(ba, ba);
    const double h = bb > 0 ? std::clamp(dot(pa, ba) / bb, 0.0, 1.0) : 0.0;
    return len({pa[0] - ba[0] * h, pa[1] - ba[1] * h, pa[2] - ba[2] * h}) - e.r;
  }
  const V u = ellipsoid_u(e, p);
  const double k0 = len(u), k1 = len({u[0] / e.radii[0], u[1] / e.radii[1], u[2] / e.radii[2]});
  return k1 > 0 ? k0 * (k0 - 1) / k1 : -e.r;
}

/// A lower bound of prim_distance over the ball of `radius` around c, where it is positive (see the
/// top of the file).
double prim_ball_bound(const ShapeField::Prim& e, const V& c, double radius) {
  if (e.mesh) return e.mesh->lower_bound({c[0] - radius, c[1] - radius, c[2] - radius}, {c[0] + radius, c[1] + radius, c[2] + radius});
  if (e.capsule) return prim_distance(e, c) - radius;
  return e.r * (len(ellipsoid_u(e, c)) - 1) - radius;
}

}  // namespace

const char* shape_kind_name(ShapeKind k) {
  switch (k) {
    case ShapeKind::Ellipsoid: return "ellipsoid";
    case ShapeKind::Sphere: return "sphere";
    case ShapeKind::Capsule: return "capsule";
    case ShapeKind::Mesh: return "mesh";
    case ShapeKind::Vdb: return "vdb";
  }
  return "?";
}

double smooth_min(double a, double b, double k) {
  if (!(k > 0)) return std::min(a, b);
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}

namespace {
/// S(u) = u^2 (3 - 2u) of u clamped to [0, 1]: the falloff's and the modifiers' ramps.
double smooth01(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}
}  // namespace

double shape_falloff(double d, double falloff) { return smooth01(0.5 - d / falloff); }

std::vector<std::pair<std::string, std::string>> shape_problems(const ShapeParams& sp) {
  std::vector<std::pair<std::string, std::string>> out;
  if (sp.sources.size() > kMaxShapeSources)
    return {{"/shape/sources", std::to_string(sp.sources.size()) + " sources; at most " + std::to_string(kMaxShapeSources)}};
  const size_t meshes = size_t(std::count_if(sp.sources.begin(), sp.sources.end(),
                                              [](const ShapeSource& s) { return s.kind == ShapeKind::Mesh || s.kind == ShapeKind::Vdb; }));
  if (meshes > kMaxMeshSources)
    out.push_back({"/shape/sources", std::to_string(meshes) + " mesh and vdb sources; at most " + std::to_string(kMaxMeshSources) +
                                         " (each holds a distance lattice of up to 128 MiB)"});
  for (const auto& [m, ptr] : {std::pair<const ShapeModifier*, const char*>{&sp.billowy, "/shape/billowy/amplitude"},
                                {&sp.wispy, "/shape/wispy/amplitude"}})
    if (m->on() && sp.sources.empty())
      out.push_back({ptr, shortest_text(m->amplitude) + " needs shape sources (/shape/sources): the modifiers move their surface"});
  if (sp.floor && sp.ceiling && !(*sp.ceiling > *sp.floor))
    out.push_back({"/shape/ceiling", shortest_text(*sp.ceiling) + " must be above /shape/floor (" + shortest_text(*sp.floor) + ")"});
  for (size_t i = 0; i < sp.sources.size(); ++i) {
    const ShapeSource& s = sp.sources[i];
    const std::string ptr = "/shape/sources/" + std::to_string(i);
    if (!s.kind) {
      out.push_back({ptr + "/kind", "missing; expected one of: ellipsoid | sphere | capsule | mesh | vdb"});
      continue;
    }
    const ShapeKind k = *s.kind;
    const std::string kn = shape_kind_name(k);
    auto need = [&](bool has, bool wanted, const char* key) {
      if (has && !wanted) out.push_back({ptr + "/" + key, "is not a key of a " + kn});
      if (!has && wanted) out.push_back({ptr, "a " + kn + " needs \"" + key + "\""});
    };
    const bool mesh = k == ShapeKind::Mesh || k == ShapeKind::Vdb, vdb = k == ShapeKind::Vdb;
    need(bool(s.center), k != ShapeKind::Capsule && !mesh, "center");
    need(bool(s.radii), k == ShapeKind::Ellipsoid, "radii");
    need(bool(s.radius), k == ShapeKind::Sphere || k == ShapeKind::Capsule, "radius");
    need(bool(s.file), mesh, "file");
    if (s.fit && !mesh) out.push_back({ptr + "/fit", "is not a key of a " + kn + " (only a mesh or a vdb is fitted)"});
    for (const auto& [has, key] : {std::pair<bool, const char*>{bool(s.grid), "grid"}, {bool(s.iso), "iso"}, {bool(s.up), "up"}})
      if (has && !vdb) out.push_back({ptr + "/" + key, "is not a key of a " + kn + " (only of a vdb source)"});
    need(bool(s.a), k == ShapeKind::Capsule, "a");
    need(bool(s.b), k == ShapeKind::Capsule, "b");
    if (k == ShapeKind::Capsule && !uniform(s.scale))
      out.push_back({ptr + "/scale", "a capsule takes a uniform scale [s, s, s] (a stretched capsule is no capsule)"});
  }
  return out;
}

ShapeField::ShapeField(const ShapeParams& s, double voxel_size, uint64_t seed)
    : blend_(s.blend), falloff_(s.falloff), floor_(s.floor), ceiling_(s.ceiling), billowy_(s.billowy), wispy_(s.wispy),
      seed_(seed), step_(std::max(s.falloff / 4, 1e-3)) {
  // A mesh's lattice holds the true distance out to the band; beyond it the field is +-band. Where
  // the smooth union could still reach below falloff / 2 from there it must be exact: the fold
  // lowers a distance by at most blend / 4 per source, and only within blend of another, and the
  // billows by at most their amplitude (a band without them would leave the clamped +band value
  // for the billows to lift into specks of cloud far from the mesh).
  const double band = falloff_ / 2 + blend_ * (1 + double(s.sources.size()) / 4) + s.billowy.amplitude;
  for (const ShapeSource& src : s.sources) prims_.push_back(resolve(src, voxel_size, band));
}

void fit_sources(ShapeParams& sp, const ShapeVec& origin, const std::array<uint32_t, 3>& n, double vs) {
  for (ShapeSource& s : sp.sources) {
    if (!s.fit || (!s.mesh && !s.vdb)) continue;
    double R[3][3];
    rotation(s.rotate, R);
    const std::array<V, 2> b = turned_box(s, R, 1.0);
    const double margin = sp.falloff / 2 + sp.billowy.amplitude + vs;  // room for the edge and the billows
    double f = 1e300;
    for (int i = 0; i < 3; ++i) {
      const double room = std::max(n[i] * vs - 2 * margin, 0.5 * n[i] * vs);
      if (b[1][i] - b[0][i] > 0) f = std::min(f, room / (b[1][i] - b[0][i]));
    }
    if (!(f < 1e300)) f = 1;
    const V c = mesh_centre(s);
    s.fit_scale = f;
    for (int i = 0; i < 3; ++i) s.fit_offset[i] = origin[i] + n[i] * vs / 2 - c[i] - f * (b[0][i] + b[1][i]) / 2;
  }
}

double ShapeField::union_distance(const ShapeVec& p) const {
  double d = prim_distance(prims_[0], p);
  for (size_t i = 1; i < prims_.size(); ++i) d = smooth_min(d, prim_distance(prims_[i], p), blend_);
  return d;
}

double ShapeField::cut(const ShapeVec& p, double d) const {
  // The cuts: intersections with the half-spaces above the floor and below the ceiling.
  if (floor_) d = std::max(d, *floor_ - p[1]);
  if (ceiling_) d = std::max(d, p[1] - *ceiling_);
  return d;
}

double ShapeField::distance(const ShapeVec& p) const { return cut(p, union_distance(p)); }

namespace {

/// Weight of a modifier from height and depth: the smooth height ramp times the depth mask.
double modifier_weight(const ShapeModifier& m, double y, double d) {
  double w = 1;
  if (m.heights) {
    const double a = (*m.heights)[0], b = (*m.heights)[1];
    w = a == b ? (y >= a ? 1.0 : 0.0) : smooth01((y - a) / (b - a));
  }
  if (d < 0) w *= 1 - smooth01(-d / m.depth);
  return w;
}

// The noise has no period to keep (shapes do not tile): the largest lattice period, so it never
// repeats inside a volume.
const noise3d::Period kNoTile = noise3d::Period::cube(noise3d::kMaxPeriod);

/// fBm of `m` at p (metres) in [0, 1]: octave k at p * 2^k / period, weight gain^k, the sum divided
/// by the weights' sum. Billowy: Worley domes; wispy: Perlin advected along curl noise.
double modifier_noise(const ShapeModifier& m, const ShapeVec& p, uint64_t seed, bool billowy) {
  const double f = 1 / m.period;
  ShapeVec q{p[0] * f, p[1] * f, p[2] * f};
  if (!billowy && m.warp > 0) {  // advect the lookup along a divergence-free flow: fibres, not blobs
    const std::array<double, 3> c = noise3d::curl(q[0] * 0.5, q[1] * 0.5, q[2] * 0.5, kNoTile, seed ^ 0xC0A1ull);
    for (int i = 0; i < 3; ++i) q[i] += m.warp * c[i];
  }
  double sum = 0, wsum = 0, w = 1, scale = 1;
  for (int k = 0; k < m.octaves; ++k, w *= m.gain, scale *= 2) {
    const uint64_t sk = seed + uint64_t(k) * 0x9E3779B97F4A7C15ull;
    const double x = q[0] * scale, y = q[1] * scale, z = q[2] * scale;
    double v;
    if (billowy) {  // a dome over each cell's feature point: sqrt(1 - F1^2), round lobes, creased between
      const double f1 = std::min(noise3d::worley(x, y, z, kNoTile, sk).f1, 1.0);
      v = std::sqrt(1 - f1 * f1);
    } else {
      v = 0.5 + 0.5 * noise3d::perlin_d(x, y, z, kNoTile, sk) / noise3d::kPerlinBound;
    }
    sum += w * v, wsum += w;
  }
  return wsum > 0 ? std::clamp(sum / wsum, 0.0, 1.0) : 0.0;
}

}  // namespace

double ShapeField::modify(const ShapeVec& p, double d) const {
  double out = d;
  if (billowy_.on()) {
    const double w = modifier_weight(billowy_, p[1], d);
    if (w > 0) out -= billowy_.amplitude * (w * modifier_noise(billowy_, p, seed_ ^ 0xB111011ull, true));
  }
  if (wispy_.on()) {
    double w = modifier_weight(wispy_, p[1], d);
    if (w > 0 && wispy_.downwind > 0) {  // the outward normal against the wind: stronger downwind
      const double wl = len(wispy_.wind);
      double g[3], gl2 = 0;
      for (int a = 0; a < 3; ++a) {
        ShapeVec lo = p, hi = p;
        lo[a] -= step_, hi[a] += step_;
        g[a] = union_distance(hi) - union_distance(lo);
        gl2 += g[a] * g[a];
      }
      const double c = wl > 0 && gl2 > 0 ? (g[0] * wispy_.wind[0] + g[1] * wispy_.wind[1] + g[2] * wispy_.wind[2]) / (wl * std::sqrt(gl2)) : 0.0;
      w *= 1 - wispy_.downwind * (1 - std::clamp(0.5 + 0.5 * c, 0.0, 1.0));
    }
    if (w > 0) out += wispy_.amplitude * (w * modifier_noise(wispy_, p, seed_ ^ 0x5715917ull, false));
  }
  return out;
}

double ShapeField::modified_distance(const ShapeVec& p) const { return cut(p, modify(p, union_distance(p))); }

double ShapeField::density(const ShapeVec& p) const {
  const double u = union_distance(p), d = cut(p, u);
  // The modified union lies in [u - billowy, u + wispy] (each term is amplitude times a product of
  // factors in [0, 1], and rounding is monotone), so after the cuts d' lies in [d - billowy,
  // d + wispy]: where either end already saturates s, s is that value.
  if (d - billowy_.amplitude >= falloff_ / 2) return 0;
  if (d + wispy_.amplitude <= -falloff_ / 2) return 1;
  return shape_falloff(cut(p, modify(p, u)), falloff_);
}

bool ShapeField::zero_in_ball(const ShapeVec& c, double radius) const {
  double lb = prim_ball_bound(prims_[0], c, radius);
  for (size_t i = 1; i < prims_.size(); ++i) lb = smooth_min(lb, prim_ball_bound(prims_[i], c, radius), blend_);
  // Billowy moves the union's surface out by at most its amplitude (wispy only moves it in); the
  // cuts come after the modifiers.
  lb -= billowy_.amplitude;
  // max(a, b) is bounded below by max of the bounds; the half-spaces' distances are exact.
  if (floor_) lb = std::max(lb, *floor_ - (c[1] + radius));
  if (ceiling_) lb = std::max(lb, (c[1] - radius) - *ceiling_);
  // Rounding of d and of the bound is far below a millionth of the scales involved.
  const double scale = 1 + falloff_ + radius + std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2])});
  return lb >= falloff_ / 2 + 1e-6 * scale;
}

std::array<ShapeVec, 2> ShapeField::support_box() const {
  // s > 0 needs d < falloff / 2, and the fold lowers min_i d_i by at most (n - 1) blend / 4, so
  // some source has d_i < g: within r + g of a capsule's segment, or, for an ellipsoid, L < g, that
  // is k0 < 1 + g / rmin: inside the ellipsoid with its radii grown by that factor.
  const double g = falloff_ / 2 + double(prims_.size() - 1) * blend_ / 4 + billowy_.amplitude;
  std::array<ShapeVec, 2> box{{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}}};
  for (const Prim& e : prims_) {
    for (int a = 0; a < 3; ++a) {
      double lo, hi;
      if (e.mesh) {  // inside the mesh or near it; the lattice's interpolation adds up to a sample
        lo = e.mesh->mesh_lo()[a] - g - 2 * e.mesh->spacing(), hi = e.mesh->mesh_hi()[a] + g + 2 * e.mesh->spacing();
      } else if (e.capsule) {
        lo = std::min(e.a[a], e.b[a]) - e.r - g, hi = std::max(e.a[a], e.b[a]) + e.r + g;
      } else {
        const double f = 1 + g / e.r;  // half extent of the grown ellipsoid along world axis a
        const double h = f * std::hypot(e.rot[a][0] * e.radii[0], e.rot[a][1] * e.radii[1], e.rot[a][2] * e.radii[2]);
        lo = e.c[a] - h, hi = e.c[a] + h;
      }
      box[0][a] = std::min(box[0][a], lo), box[1][a] = std::max(box[1][a], hi);
    }
  }
  // s > 0 needs floor - y < falloff / 2 and y - ceiling < falloff / 2 (the cuts follow the modifiers).
  if (floor_) box[0][1] = std::max(box[0][1], *floor_ - falloff_ / 2);
  if (ceiling_) box[1][1] = std::min(box[1][1], *ceiling_ + falloff_ / 2);
  return box;
}

std::optional<ShapeVec> ShapeField::nonzero_at_side_faces(const ShapeVec& origin, const std::array<uint32_t, 3>& n,
                                                           double vs) const {
  auto at = [&](int a, uint32_t i) { return origin[a] + (i + 0.5) * vs; };
  const std::array<ShapeVec, 2> box = support_box();
  for (int a : {0, 2}) {
    const double margin = 1e-6 * (1 + std::abs(at(a, 0)) + std::abs(at(a, n[a] - 1)));
    if (box[0][a] > at(a, 0) + margin && box[1][a] < at(a, n[a] - 1) - margin) continue;  // the usual case
    const int b = 2 - a;  // the other horizontal axis; the face spans b and y in patches of 16 x 16
    for (uint32_t side : {0u, n[a] - 1})
      for (uint32_t j0 = 0; j0 < n[1]; j0 += 16)
        for (uint32_t k0 = 0; k0 < n[b]; k0 += 16) {
          const uint32_t j1 = std::min(n[1], j0 + 16) - 1, k1 = std::min(n[b], k0 + 16) - 1;
          ShapeVec mid;
          mid[a] = at(a, side), mid[1] = (at(1, j0) + at(1, j1)) / 2, mid[b] = (at(b, k0) + at(b, k1)) / 2;
          if (zero_in_ball(mid, std::hypot(at(1, j1) - mid[1], at(b, k1) - mid[b]))) continue;
          for (uint32_t j = j0; j <= j1; ++j)
            for (uint32_t k = k0; k <= k1; ++k) {
              ShapeVec q;
              q[a] = at(a, side), q[1] = at(1, j), q[b] = at(b, k);
              if (density(q) > 0) return q;
            }
        }
  }
  return std::nullopt;
}

}  // namespace cloudgen
