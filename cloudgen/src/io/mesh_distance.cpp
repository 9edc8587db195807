// The distance to a placed mesh (mesh_source.h): OpenVDB's narrow-band level set of the triangles
// (exact distances near the surface, inside and outside told apart by its flood fill, which stands
// self-intersections), copied to a dense lattice so a sample is one read and a box's least sample
// one pass over 8^3-sample blocks. An open mesh has no inside: its unsigned distance is used.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Count.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <tbb/parallel_for.h>

#include "cloudgen/errors.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/schema.h"
#include "vdb_internal.h"

namespace cloudgen {

int MeshDistance::setup(double band, const std::string& what) {
  // The narrow band's half width in samples: at least `band`, plus one sample.
  const int half = int(std::ceil(band / h_)) + 1;
  band_ = half * h_;
  const double margin = band_ + 2 * h_;  // the lattice's edge samples lie outside the band
  size_t count = 1;
  for (int a = 0; a < 3; ++a) {
    lo_[a] = mesh_lo_[a] - margin;
    n_[a] = int64_t(std::ceil((mesh_hi_[a] - mesh_lo_[a] + 2 * margin) / h_)) + 1;
    count *= size_t(n_[a]);
    if (count > kMaxMeshSamples)
      throw InputError(what + ": the source's distance lattice would need over " + std::to_string(kMaxMeshSamples) +
                       " samples at " + std::to_string(h_) + " m; make it smaller or the voxels larger");
  }
  v_.assign(count, 0.0f);
  return half;
}

void MeshDistance::finish() {
  for (int a = 0; a < 3; ++a) nb_[a] = (n_[a] + 7) / 8;
  bmin_.assign(size_t(nb_[0] * nb_[1] * nb_[2]), 1e30f);
  for (int64_t k = 0; k < n_[2]; ++k)
    for (int64_t j = 0; j < n_[1]; ++j)
      for (int64_t i = 0; i < n_[0]; ++i) {
        float& b = bmin_[size_t(((k / 8) * nb_[1] + j / 8) * nb_[0] + i / 8)];
        b = std::min(b, v_[size_t((k * n_[1] + j) * n_[0] + i)]);
      }
}

MeshDistance::MeshDistance(const TriangleMesh& m, const std::array<double, 12>& T, double h, double band) : h_(h) {
  openvdb::initialize();
  // The placed points, relative to the lattice's corner (floats keep millimetres there).
  std::vector<std::array<double, 3>> w(m.points.size());
  mesh_lo_ = {1e300, 1e300, 1e300}, mesh_hi_ = {-1e300, -1e300, -1e300};
  std::vector<char> used(m.points.size(), 0);
  for (const auto& t : m.triangles)
    for (uint32_t v : t) used[v] = 1;
  for (size_t v = 0; v < m.points.size(); ++v) {
    const auto& q = m.points[v];
    for (int a = 0; a < 3; ++a) w[v][a] = T[4 * a] * q[0] + T[4 * a + 1] * q[1] + T[4 * a + 2] * q[2] + T[4 * a + 3];
    if (used[v])
      for (int a = 0; a < 3; ++a) mesh_lo_[a] = std::min(mesh_lo_[a], w[v][a]), mesh_hi_[a] = std::max(mesh_hi_[a], w[v][a]);
  }
  const int half = setup(band, m.file);
  std::vector<openvdb::Vec3s> pts(w.size());
  for (size_t v = 0; v < w.size(); ++v)
    pts[v] = openvdb::Vec3s(float((w[v][0] - lo_[0]) / h), float((w[v][1] - lo_[1]) / h), float((w[v][2] - lo_[2]) / h));
  std::vector<openvdb::Vec3I> tris(m.triangles.size());
  for (size_t t = 0; t < tris.size(); ++t) tris[t] = openvdb::Vec3I(m.triangles[t][0], m.triangles[t][1], m.triangles[t][2]);
  // Index space = the lattice: sample (i, j, k) sits at lo_ + (i, j, k) h; distances in samples.
  const auto xform = openvdb::math::Transform::createLinearTransform(1.0);
  signed_ = m.open_edges == 0;
  openvdb::FloatGrid::Ptr g;
  if (signed_) {
    g = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, pts, tris, float(half));
  } else {
    const std::vector<openvdb::Vec4I> quads;
    g = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*xform, pts, tris, quads, float(half));
  }
  const float lim = float(half);
  tbb::parallel_for(int64_t(0), n_[2], [&](int64_t k) {
    auto acc = g->getConstAccessor();
    for (int64_t j = 0; j < n_[1]; ++j)
      for (int64_t i = 0; i < n_[0]; ++i) {
        float d = acc.getValue(openvdb::Coord(int(i), int(j), int(k)));
        if (!std::isfinite(d)) d = lim;
        v_[size_t((k * n_[1] + j) * n_[0] + i)] = float(std::clamp(d, signed_ ? -lim : 0.0f, lim) * h);
      }
  });
  finish();
}

MeshDistance::MeshDistance(const VdbShape& s, const std::array<double, 12>& T, double h, double band) : h_(h) {
  openvdb::initialize();
  const auto src = std::static_pointer_cast<const openvdb::FloatGrid>(s.grid_ptr);
  // The placed box: T applied to the corners of the grid's y-up box.
  mesh_lo_ = {1e300, 1e300, 1e300}, mesh_hi_ = {-1e300, -1e300, -1e300};
  for (int c = 0; c < 8; ++c) {
    const double q[3] = {c & 1 ? s.hi[0] : s.lo[0], c & 2 ? s.hi[1] : s.lo[1], c & 4 ? s.hi[2] : s.lo[2]};
    for (int a = 0; a < 3; ++a) {
      const double w = T[4 * a] * q[0] + T[4 * a + 1] * q[1] + T[4 * a + 2] * q[2] + T[4 * a + 3];
      mesh_lo_[a] = std::min(mesh_lo_[a], w), mesh_hi_[a] = std::max(mesh_hi_[a], w);
    }
  }
  setup(band, s.file);
  // T's linear part L and its inverse: a lattice point w goes back to q = L^-1 (w - t) in the y-up
  // frame of the file; distances there scale by k = |det L|^(1/3) (exact for an even scale).
  const openvdb::Mat3d L(T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10]);
  const openvdb::Mat3d Li = L.inverse();
  const double k = std::cbrt(std::abs(L.det()));
  // The level set, with a band covering `band` (in the file's voxels) on both sides; a fog volume
  // negated first, so inside (density above iso) is below the isovalue as for a level set.
  const double vs = src->voxelSize()[0];
  const float width = float(band / k / vs + 3);
  openvdb::FloatGrid::Ptr ls;
  if (s.level_set) {
    ls = openvdb::tools::levelSetRebuild(*src, 0.0f, width, width);
  } else {
    openvdb::FloatGrid::Ptr neg = src->deepCopy();
    for (auto it = neg->beginValueAll(); it; ++it) it.setValue(-*it);
    ls = openvdb::tools::levelSetRebuild(*neg, float(-s.iso), width, width);
  }
  const float lim = float(band_);
  tbb::parallel_for(int64_t(0), n_[2], [&](int64_t kk) {
    auto acc = ls->getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(acc, ls->transform());
    for (int64_t j = 0; j < n_[1]; ++j)
      for (int64_t i = 0; i < n_[0]; ++i) {
        const openvdb::Vec3d w(lo_[0] + i * h, lo_[1] + j * h, lo_[2] + kk * h);
        const openvdb::Vec3d q = Li * (w - openvdb::Vec3d(T[3], T[7], T[11]));
        // y-up back to the file's frame: (x, y, z) -> (x, -z, y) for a z-up file.
        const openvdb::Vec3d f = s.up == 'z' ? openvdb::Vec3d(q.x(), -q.z(), q.y()) : q;
        float d = float(sampler.wsSample(f) * k);
        if (!std::isfinite(d)) d = lim;
        v_[size_t((kk * n_[1] + j) * n_[0] + i)] = std::clamp(d, -lim, lim);
      }
  });
  finish();
}

double MeshDistance::sample(int64_t i, int64_t j, int64_t k) const {
  i = std::clamp<int64_t>(i, 0, n_[0] - 1), j = std::clamp<int64_t>(j, 0, n_[1] - 1), k = std::clamp<int64_t>(k, 0, n_[2] - 1);
  return v_[size_t((k * n_[1] + j) * n_[0] + i)];
}

double MeshDistance::distance(const std::array<double, 3>& p) const {
  double u[3];
  int64_t c[3];
  for (int a = 0; a < 3; ++a) {
    // Beyond the lattice every sample is +band_ (its edge lies outside the band): so is the field.
    u[a] = std::clamp((p[a] - lo_[a]) / h_, 0.0, double(n_[a] - 1));
    c[a] = std::min<int64_t>(int64_t(u[a]), n_[a] - 2 < 0 ? 0 : n_[a] - 2);
    u[a] -= double(c[a]);
  }
  double r = 0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx)
        r += (dx ? u[0] : 1 - u[0]) * (dy ? u[1] : 1 - u[1]) * (dz ? u[2] : 1 - u[2]) * sample(c[0] + dx, c[1] + dy, c[2] + dz);
  return r;
}

double MeshDistance::lower_bound(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const {
  int64_t b0[3], b1[3];
  for (int a = 0; a < 3; ++a) {
    // Samples floor(u_lo) .. floor(u_hi) + 1, clamped as distance() clamps.
    const double ul = std::clamp((lo[a] - lo_[a]) / h_, 0.0, double(n_[a] - 1));
    const double uh = std::clamp((hi[a] - lo_[a]) / h_, 0.0, double(n_[a] - 1));
    const int64_t s0 = std::max<int64_t>(0, int64_t(std::floor(ul)) - 1);
    const int64_t s1 = std::min<int64_t>(n_[a] - 1, int64_t(std::floor(uh)) + 2);
    b0[a] = s0 / 8, b1[a] = s1 / 8;
  }
  float m = 1e30f;
  for (int64_t k = b0[2]; k <= b1[2]; ++k)
    for (int64_t j = b0[1]; j <= b1[1]; ++j)
      for (int64_t i = b0[0]; i <= b1[0]; ++i) m = std::min(m, bmin_[size_t((k * nb_[1] + j) * nb_[0] + i)]);
  return m;
}

}  // namespace cloudgen

namespace cloudgen {

VdbShape read_vdb_shape(const std::string& path, const std::string& grid, double iso, char up, const std::string& what) {
  vdb::init();
  const openvdb::GridPtrVec grids = vdb::read_grids(path);  // the checked reader: the seal, or a child's read
  openvdb::FloatGrid::Ptr g;
  std::string names;
  for (const auto& b : grids) {
    names += (names.empty() ? "" : ", ") + b->getName();
    const bool wanted = grid.empty() ? (b->getName() == "density" || !g) : b->getName() == grid;
    if (!wanted) continue;
    if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(b)) {
      if (grid.empty() && g && g->getName() == "density") continue;  // "density" wins over a first float grid
      g = f;
    } else if (!grid.empty()) {
      throw InputError(what + ": grid \"" + grid + "\" holds " + b->valueType() +
                       " values; a shape source needs a float grid (a level set or a fog volume)");
    }
  }
  if (!g)
    throw InputError(what + ": " + (grid.empty() ? std::string("no float grid") : "no grid \"" + grid + "\"") +
                     " (the file's grids: " + names + ")");
  if (g->activeVoxelCount() == 0) throw InputError(what + ": grid \"" + g->getName() + "\" has no active voxels");
  VdbShape s;
  s.file = path, s.grid = g->getName(), s.iso = iso;
  s.level_set = g->getGridClass() == openvdb::GRID_LEVEL_SET;
  if (up) {
    s.up = up;
  } else {
    try {
      s.up = vdb::up_axis_of(g->transform(), path);
    } catch (const InputError&) {
      s.up = 'y';
    }
  }
  if (!s.level_set) {
    const float hi = openvdb::tools::minMax(g->tree()).max();
    if (!(hi > iso))
      throw InputError(what + ": grid \"" + s.grid + "\" (a fog volume) never exceeds iso " + shortest_text(iso) +
                       " (its largest value is " + shortest_text(hi) + "): set shape.sources.N.iso lower");
  }
  // The y-up box of the active voxels' corners.
  const openvdb::CoordBBox b = g->evalActiveVoxelBoundingBox();
  s.lo = {1e300, 1e300, 1e300}, s.hi = {-1e300, -1e300, -1e300};
  for (int c = 0; c < 8; ++c) {
    const openvdb::Vec3d idx(c & 1 ? b.max().x() + 0.5 : b.min().x() - 0.5, c & 2 ? b.max().y() + 0.5 : b.min().y() - 0.5,
                             c & 4 ? b.max().z() + 0.5 : b.min().z() - 0.5);
    const openvdb::Vec3d w = vdb::to_y_up(g->transform().indexToWorld(idx), s.up);
    for (int a = 0; a < 3; ++a) s.lo[a] = std::min(s.lo[a], w[a]), s.hi[a] = std::max(s.hi[a], w[a]);
  }
  const std::string key = vdb::file_seal(path) + "|" + s.grid + "|" + shortest_text(iso) + "|" + s.up;
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char ch : key) h = (h ^ ch) * 0x100000001b3ull;
  s.fnv1a = h;
  s.grid_ptr = g;
  return s;
}

}  // namespace cloudgen
