// libFuzzer target for mesh shape sources (mesh_source.h). The first byte picks the path:
//  - 0-4: a file in OBJ, PLY, STL, GLB or OFF (the rest of the input) through read_mesh_bytes:
//    Assimp runs in a child process with a CPU-time limit, so a file that makes it loop or crash
//    must come back as an InputError, never hang or crash this process (Assimp's own code is
//    fuzzed upstream; its coverage in the child is not seen here);
//  - 5: arrays (u16 points, u16 triangles, then floats and u32 indices) straight into
//    mesh_from_arrays, our checks, coverage-guided.
// A mesh that is accepted is checked (indices in range, finite points inside its box) and, when
// small, its distance lattice is built and probed: every distance finite and within the band, and
// the box bound never above a distance inside the box.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "cloudgen/mesh_source.h"
#include "fuzz_common.h"

namespace {

cloudgen::TriangleMesh from_arrays(const uint8_t* data, size_t size) {
  uint16_t np = 0, nt = 0;
  if (size >= 4) std::memcpy(&np, data, 2), std::memcpy(&nt, data + 2, 2);
  size_t at = 4;
  std::vector<std::array<float, 3>> points;
  std::vector<std::array<uint32_t, 3>> tris;
  for (uint16_t i = 0; i < np && at + 12 <= size; ++i, at += 12) {
    std::array<float, 3> p;
    std::memcpy(p.data(), data + at, 12);
    points.push_back(p);
  }
  for (uint16_t i = 0; i < nt && at + 12 <= size; ++i, at += 12) {
    std::array<uint32_t, 3> t;
    std::memcpy(t.data(), data + at, 12);
    tris.push_back(t);
  }
  return cloudgen::mesh_from_arrays(std::move(points), std::move(tris), "fuzz arrays");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {"obj", "ply", "stl", "glb", "off"};
  const int mode = data[0] % 6;
  return fuzz::guarded([&] {
    const cloudgen::TriangleMesh m = mode == 5 ? from_arrays(data + 1, size - 1)
                                               : cloudgen::read_mesh_bytes(std::vector<uint8_t>(data + 1, data + size),
                                                                           kExt[mode], "fuzz mesh");
    if (m.triangles.empty() || !(m.area > 0)) __builtin_trap();
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
