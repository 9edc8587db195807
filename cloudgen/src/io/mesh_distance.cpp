// The distance to a placed mesh (mesh_source.h): OpenVDB's narrow-band level set of the triangles
// (exact distances near the surface, inside and outside told apart by its flood fill, which stands
// self-intersections), copied to a dense lattice so a sample is one read and a box's least sample
// one pass over 8^3-sample blocks. An open mesh has no inside: its unsigned distance is used.
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <tbb/parallel_for.h>

#include "cloudgen/errors.h"
#include "cloudgen/mesh_source.h"

namespace cloudgen {

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
  // The narrow band's half width in samples: at least `band`, plus one sample.
  const int half = int(std::ceil(band / h)) + 1;
  band_ = half * h;
  const double margin = band_ + 2 * h;  // the lattice's edge samples lie outside the band: +band_
  size_t count = 1;
  for (int a = 0; a < 3; ++a) {
    lo_[a] = mesh_lo_[a] - margin;
    n_[a] = int64_t(std::ceil((mesh_hi_[a] - mesh_lo_[a] + 2 * margin) / h)) + 1;
    count *= size_t(n_[a]);
    if (count > kMaxMeshSamples)
      throw InputError(m.file + ": the mesh's distance lattice would need over " + std::to_string(kMaxMeshSamples) +
                       " samples at " + std::to_string(h) + " m; make the mesh smaller or the voxels larger");
  }
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
  v_.assign(count, 0.0f);
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
  for (int a = 0; a < 3; ++a) nb_[a] = (n_[a] + 7) / 8;
  bmin_.assign(size_t(nb_[0] * nb_[1] * nb_[2]), 1e30f);
  for (int64_t k = 0; k < n_[2]; ++k)
    for (int64_t j = 0; j < n_[1]; ++j)
      for (int64_t i = 0; i < n_[0]; ++i) {
        float& b = bmin_[size_t(((k / 8) * nb_[1] + j / 8) * nb_[0] + i / 8)];
        b = std::min(b, v_[size_t((k * n_[1] + j) * n_[0] + i)]);
      }
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
