// libFuzzer target for the mesh reader of mesh shape sources (mesh_source.h, Assimp): the first byte
// picks the format (OBJ, PLY, STL, GLB, OFF), the rest is the file. It is read or refused with
// InputError; a mesh that is read is checked (indices in range, finite points inside its box) and,
// when small, its distance lattice is built and probed: every distance finite and within the
// band, and the box bound never above a distance inside the box.
#include <cmath>
#include <cstdint>
#include <vector>

#include "cloudgen/mesh_source.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {"obj", "ply", "stl", "glb", "off"};
  const char* ext = kExt[data[0] % 5];
  const std::vector<uint8_t> bytes(data + 1, data + size);
  return fuzz::guarded([&] {
    const cloudgen::TriangleMesh m = cloudgen::read_mesh_bytes(bytes, ext, "fuzz mesh");
    if (m.triangles.empty()) __builtin_trap();
    for (const auto& t : m.triangles)
      for (uint32_t v : t) {
        if (v >= m.points.size()) __builtin_trap();
        for (int a = 0; a < 3; ++a)
          if (!std::isfinite(m.points[v][a]) || m.points[v][a] < m.lo[a] || m.points[v][a] > m.hi[a]) __builtin_trap();
      }
    if (m.triangles.size() > 2000) return;
    // Fit the mesh into a box of 100 units, lattice spacing 5 (at most about 30^3 samples).
    double ext_max = 0;
    for (int a = 0; a < 3; ++a) ext_max = std::fmax(ext_max, m.hi[a] - m.lo[a]);
    const double k = ext_max > 0 ? 100 / ext_max : 1;
    std::array<double, 12> T{};
    for (int a = 0; a < 3; ++a) T[4 * a + a] = k, T[4 * a + 3] = -k * m.lo[a];
    const cloudgen::MeshDistance d(m, T, 5.0, 10.0);
    for (int i = 0; i < 5; ++i) {
      const std::array<double, 3> p{-20.0 + 35 * i, 50.0 - 13 * i, 7.0 + 29 * i};
      const double v = d.distance(p);
      if (!std::isfinite(v) || std::fabs(v) > d.band() * 1.0001) __builtin_trap();
      if (d.lower_bound({p[0] - 3, p[1] - 3, p[2] - 3}, {p[0] + 3, p[1] + 3, p[2] + 3}) > v + 1e-3) __builtin_trap();
    }
  });
}
