// Mesh shape sources (cloudgen/mesh_source.h, `{"kind": "mesh", "file": ...}`) and `cloudgen shape`:
// a closed mesh puts cloud where its interior is (a cube and a faceted sphere against their analytic
// interiors), `fit` fills the volume, an open mesh becomes a sheet, skipping stays exact and thread
// counts give the same bytes, the mesh's content (not its name) is in the preset hash, bad meshes
// are refused naming the field, and `cloudgen shape` writes a VDB its saved preset reproduces.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "cloudgen/generate.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/preset.h"
#include "cloudgen/preset_save.h"
#include "cloudgen/shape.h"
#include "test_util.h"
#include "test_util_generate.h"

using namespace cloudgen;

namespace {

using testutil::run_cli;
using testutil::same_bytes;
using testutil::TempDir;

/// An axis-aligned box as an OBJ (12 triangles, outward faces).
std::string box_obj(double x0, double y0, double z0, double x1, double y1, double z1) {
  std::string s;
  for (int c = 0; c < 8; ++c) {
    char line[128];
    std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", c & 1 ? x1 : x0, c & 2 ? y1 : y0, c & 4 ? z1 : z0);
    s += line;
  }
  // Corners 1-based: bit 0 = x, bit 1 = y, bit 2 = z.
  s += "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";
  return s;
}

/// A UV sphere as an OBJ: `rings` x `segments` quads (triangulated by the reader), closed.
std::string sphere_obj(double cx, double cy, double cz, double r, int rings, int segments) {
  std::string s;
  char line[128];
  std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", cx, cy + r, cz);
  s += line;
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
      std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", cx + r * std::sin(th) * std::cos(ph), cy + r * std::cos(th),
                    cz + r * std::sin(th) * std::sin(ph));
      s += line;
    }
  std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", cx, cy - r, cz);
  s += line;
  const int bottom = 2 + (rings - 1) * segments;  // 1-based
  auto at = [&](int i, int j) { return 2 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) s += "f 1 " + std::to_string(at(1, j + 1)) + " " + std::to_string(at(1, j)) + "\n";
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j)
      s += "f " + std::to_string(at(i, j)) + " " + std::to_string(at(i, j + 1)) + " " + std::to_string(at(i + 1, j + 1)) + " " +
           std::to_string(at(i + 1, j)) + "\n";
  for (int j = 0; j < segments; ++j)
    s += "f " + std::to_string(bottom) + " " + std::to_string(at(rings - 1, j)) + " " + std::to_string(at(rings - 1, j + 1)) + "\n";
  return s;
}

constexpr int kN = 64;
constexpr double kVs = 10;
double centre(int i) { return (i + 0.5) * kVs; }

/// 64^3 voxels of 10 m; with `neutral` the noise R is exactly 1 and the threshold 0.5, so density
/// > 0 exactly where the shape's distance is negative (test_shape.cpp does the same).
Preset meshed(const std::string& shape, bool neutral, const std::string& source = "mesh.json") {
  std::string j = R"({"resolution": [64, 64, 64], "voxel_size": 10, "tiling": false, "shape": )" + shape;
  if (neutral) j += R"(, "threshold": 0.5, "channels": {"r": {"remap": [-1, -0.5]}})";
  return parse_preset(j + "}", source);
}

template <class F>
double iou(const Volume& v, F inside) {
  size_t inter = 0, uni = 0;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const bool a = v.density[v.index(x, y, z)] > 0, b = inside(centre(x), centre(y), centre(z));
        inter += a && b, uni += a || b;
      }
  return uni ? double(inter) / uni : 0.0;
}

std::string mesh_source(const std::string& file, const std::string& extra = "") {
  return R"({"falloff": 100, "sources": [{"kind": "mesh", "file": ")" + file + "\"" + extra + "}]}";
}

std::string error_of(const std::string& json, const std::string& source = "bad.json") {
  try {
    parse_preset(json, source);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// A closed cube and a faceted sphere: with the noise neutralised the cloud is the set of voxel
// centres inside the mesh; with the noise eroding it stays within falloff / 2 of it. The sphere's
// facets (24 x 48) lie within r (1 - cos(pi / 24)) = 1.5 m of the analytic sphere.
TEST(MeshSource, ClosedMeshPutsCloudInsideItself) {
  TempDir dir;
  testutil::write_text(dir / "cube.obj", box_obj(120, 150, 130, 500, 430, 520));
  testutil::write_text(dir / "sphere.obj", sphere_obj(320, 330, 310, 170, 24, 48));
  auto in_cube = [](double x, double y, double z, double g) {
    return x > 120 - g && x < 500 + g && y > 150 - g && y < 430 + g && z > 130 - g && z < 520 + g;
  };
  auto in_sphere = [](double x, double y, double z, double g) { return std::hypot(x - 320, y - 330, z - 310) < 170 + g; };
  for (int which = 0; which < 2; ++which) {
    SCOPED_TRACE(which ? "sphere" : "cube");
    const std::string file = dir / (which ? "sphere.obj" : "cube.obj");
    auto inside = [&](double x, double y, double z, double g) { return which ? in_sphere(x, y, z, g) : in_cube(x, y, z, g); };
    const Volume neutral = generate(meshed(mesh_source(file), true));
    const Volume eroded = generate(meshed(mesh_source(file), false));
    const double a = iou(neutral, [&](double x, double y, double z) { return inside(x, y, z, 0); });
    const double b = iou(eroded, [&](double x, double y, double z) { return inside(x, y, z, 0); });
    std::printf("  IoU %.4f neutral, %.4f eroded\n", a, b);
    EXPECT_GE(a, which ? 0.97 : 0.995);
    EXPECT_GE(b, 0.7);
    size_t beyond = 0;  // cloud farther than falloff / 2 (+ the facets) outside the mesh
    for (int z = 0; z < kN; ++z)
      for (int y = 0; y < kN; ++y)
        for (int x = 0; x < kN; ++x)
          beyond += eroded.density[eroded.index(x, y, z)] > 0 && !inside(centre(x), centre(y), centre(z), 52);
    EXPECT_EQ(beyond, 0u);
  }
}

// The lattice's distance against the analytic one (the cube's, outside and inside), and the box
// bound never above a distance inside the box.
TEST(MeshSource, DistanceIsTheCubesAndTheBoundHolds) {
  TempDir dir;
  testutil::write_text(dir / "cube.obj", box_obj(0, 0, 0, 100, 100, 100));
  const TriangleMesh m = read_mesh(dir / "cube.obj", "cube");
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_EQ(m.open_edges, 0u);
  EXPECT_NEAR(m.area, 60000, 1e-6);
  const std::array<double, 12> T{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  const MeshDistance d(m, T, 5.0, 40.0);
  EXPECT_TRUE(d.signed_distance());
  EXPECT_GE(d.band(), 40.0);
  auto exact = [](double x, double y, double z) {
    const double q[3] = {std::abs(x - 50) - 50, std::abs(y - 50) - 50, std::abs(z - 50) - 50};
    const double out = std::hypot(std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0));
    return out + std::min(std::max({q[0], q[1], q[2]}), 0.0);
  };
  double worst = 0;
  for (double x = -30; x <= 130; x += 7.3)
    for (double y = -30; y <= 130; y += 11.1)
      for (double z = -30; z <= 130; z += 9.7) {
        const double e = std::clamp(exact(x, y, z), -d.band(), d.band()), v = d.distance({x, y, z});
        // Trilinear between exact samples: off by at most the spacing near the cube's edges.
        worst = std::max(worst, std::abs(v - e));
        ASSERT_NEAR(v, e, 5.0) << x << " " << y << " " << z;
        const double lb = d.lower_bound({x - 6, y - 6, z - 6}, {x + 6, y + 6, z + 6});
        for (double dx : {-6.0, 0.0, 6.0})
          for (double dz : {-6.0, 6.0}) ASSERT_LE(lb, d.distance({x + dx, y + dx / 2, z + dz}) + 1e-9);
      }
  std::printf("  largest |lattice - exact| %.3f m (spacing 5 m)\n", worst);
  EXPECT_EQ(d.distance({1e6, 0, 0}), d.band());
}

// `fit` scales a mesh of any units evenly and centres it so it fills the volume less the margin
// falloff / 2 + one voxel; the cube's cloud then spans that room on its longest axis.
TEST(MeshSource, FitFillsTheVolume) {
  TempDir dir;
  testutil::write_text(dir / "unit.obj", box_obj(-1, -0.5, -0.25, 1, 0.5, 0.25));  // 2 x 1 x 0.5 units
  const Volume v = generate(meshed(mesh_source(dir / "unit.obj", R"(, "fit": true)"), true));
  int lo[3] = {kN, kN, kN}, hi[3] = {-1, -1, -1};
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x)
        if (v.density[v.index(x, y, z)] > 0) {
          const int c[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
        }
  // Room on x: 640 - 2 (50 + 10) = 520 m, centred: x in [60, 580] m, voxels 6 .. 57; y and z in
  // proportion (260 m and 130 m), centred on 320 m.
  EXPECT_EQ(lo[0], 6);
  EXPECT_EQ(hi[0], 57);
  EXPECT_NEAR((lo[1] + hi[1] + 1) * 5.0, 320, 10);
  EXPECT_NEAR((hi[1] - lo[1] + 1) * 10.0, 260, 20);
  EXPECT_NEAR((hi[2] - lo[2] + 1) * 10.0, 130, 20);
}

// An open mesh (one square) has no inside: a warning, and cloud only along its surface.
TEST(MeshSource, OpenMeshIsASheet) {
  TempDir dir;
  testutil::write_text(dir / "sheet.obj", "v 100 300 100\nv 540 300 100\nv 540 300 540\nv 100 300 540\nf 1 2 3 4\n");
  const TriangleMesh m = read_mesh(dir / "sheet.obj", "sheet");
  EXPECT_EQ(m.open_edges, 4u);
  const Volume v = generate(meshed(R"({"falloff": 60, "sources": [{"kind": "mesh", "file": ")" + (dir / "sheet.obj") + "\"}]}",
                                   false));
  size_t in = 0, out = 0;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x)
        if (v.density[v.index(x, y, z)] > 0) (std::abs(centre(y) - 300) < 30 ? in : out)++;
  EXPECT_GT(in, 1000u);
  EXPECT_EQ(out, 0u);
}

// Skipping never changes a byte (and skips), any thread count gives the same bytes, with a mesh
// blended with an ellipsoid.
TEST(MeshSource, SkippingIsExactAndThreadsAgree) {
  TempDir dir;
  testutil::write_text(dir / "sphere.obj", sphere_obj(250, 300, 300, 120, 12, 24));
  const Preset p = parse_preset(R"({"resolution": [80, 64, 64], "voxel_size": 10, "tiling": false,
      "channels": {"g": {"enabled": true}},
      "shape": {"blend": 80, "falloff": 120, "sources": [
        {"kind": "mesh", "file": ")" + (dir / "sphere.obj") + R"(", "scale": [1.4, 1, 1], "rotate": [0, 20, 10]},
        {"kind": "ellipsoid", "center": [480, 280, 300], "radii": [150, 90, 110]}]}})",
                                "blend.json");
  GenerateStats s_on;
  testutil::generate_every_way(p, s_on);
  EXPECT_GT(s_on.active_voxels, 0u);
  EXPECT_GT(s_on.bricks_skipped, 0u);
  std::printf("  %zu of %zu bricks skipped\n", s_on.bricks_skipped, s_on.bricks);
}

// The hash follows the mesh's content: the same mesh under another name keeps it, a moved vertex
// changes it.
TEST(MeshSource, PresetHashFollowsTheContent) {
  TempDir dir;
  testutil::write_text(dir / "a.obj", box_obj(100, 100, 100, 300, 300, 300));
  testutil::write_text(dir / "b.obj", box_obj(100, 100, 100, 300, 300, 300));
  testutil::write_text(dir / "c.obj", box_obj(100, 100, 100, 300, 300, 301));
  const std::string ha = preset_hash(meshed(mesh_source(dir / "a.obj"), false));
  EXPECT_EQ(ha, preset_hash(meshed(mesh_source(dir / "b.obj"), false)));
  EXPECT_NE(ha, preset_hash(meshed(mesh_source(dir / "c.obj"), false)));
}

// A file named in a preset is found next to it; Save as names it from the new file's folder.
TEST(MeshSource, RelativePathsFollowThePreset) {
  TempDir dir;
  std::filesystem::create_directories(dir / "meshes");
  std::filesystem::create_directories(dir / "saved");
  testutil::write_text(dir / "meshes/cube.obj", box_obj(100, 100, 100, 300, 300, 300));
  const std::string preset = R"({"resolution": [40, 40, 40], "voxel_size": 10, "tiling": false, "shape": )" +
                             mesh_source("meshes/cube.obj") + "}";
  testutil::write_text(dir / "p.json", preset);
  EXPECT_NO_THROW(load_preset(dir / "p.json"));
  const std::string text = edited_preset_text(dir / "p.json", {}, dir / "saved/q.json");
  EXPECT_NE(text.find("\"../meshes/cube.obj\""), std::string::npos) << text;
}

// Bad meshes and bad keys: each refused naming the field, the file and what is allowed.
TEST(MeshSource, BadInputNamesTheFieldAndWhatIsAllowed) {
  TempDir dir;
  testutil::write_text(dir / "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  testutil::write_text(dir / "far.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
  testutil::write_text(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  testutil::write_text(dir / "junk.obj", "this is not a mesh\n\x01\x02\x03");
  testutil::write_text(dir / "cube.obj", box_obj(0, 0, 0, 1, 1, 1));
  // A PLY header that never ends: Assimp 5.2 loops on it forever (found by fuzz_mesh); the reader's
  // child process is stopped after 2 s of CPU time.
  testutil::write_text(dir / "hang.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                         "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                                         "end_hsolideader\n0 0 0\n1 0\n");
  struct Case {
    std::string shape, expect;
  };
  const std::vector<Case> cases = {
      {mesh_source(dir / "missing.obj"), "/shape/sources/0/file"},
      {mesh_source(dir / "missing.obj"), "no such file"},
      {mesh_source(dir / "points.obj"), "no triangles"},
      {mesh_source(dir / "far.obj"), "has the coordinate 1e+30; allowed: finite, within +-1e+07"},
      {mesh_source(dir / "flat.obj"), "zero area"},
      {mesh_source(dir / "junk.obj"), "not a mesh Assimp can read"},
      {mesh_source(dir / "hang.ply"), "was still reading after 2 s of CPU time"},
      {mesh_source(""), "/shape/sources/0/file: empty"},
      {R"({"sources": [{"kind": "mesh"}]})", "a mesh needs \"file\""},
      {R"({"sources": [{"kind": "mesh", "file": ")" + (dir / "cube.obj") + R"(", "radius": 3}]})", "/shape/sources/0/radius: is not a key of a mesh"},
      {R"({"sources": [{"kind": "sphere", "center": [0, 0, 0], "radius": 3, "fit": true}]})", "only a mesh or a vdb is fitted"},
  };
  for (const Case& c : cases) {
    const std::string e = error_of(R"({"resolution": [16, 16, 16], "tiling": false, "shape": )" + c.shape + "}");
    EXPECT_NE(e.find(c.expect), std::string::npos) << "expected \"" << c.expect << "\" in: " << e;
  }
  // A pipe is refused by the one input layer, not read.
  const std::string fifo = dir / "pipe.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": )" + mesh_source(fifo) + "}").find("pipe"), std::string::npos);
}

// `cloudgen shape MESH -o OUT.vdb --save-preset P`: a VDB, and a preset that `generate` turns into
// the same bytes; the bad flags say what is allowed; an output may not replace the mesh.
TEST(MeshSource, ShapeCommandWritesACloudItsPresetReproduces) {
  TempDir dir;
  testutil::write_text(dir / "ring.obj", sphere_obj(0, 0, 0, 1, 10, 20));
  std::string out;
  ASSERT_EQ(run_cli("shape " + (dir / "ring.obj") + " -o " + (dir / "a.vdb") + " --size 800 --voxel-size 25 --save-preset " +
                        (dir / "ring.json") + " --threads 1",
                    &out),
            0)
      << out;
  EXPECT_NE(out.find("wrote"), std::string::npos) << out;
  ASSERT_EQ(run_cli("generate " + (dir / "ring.json") + " -q --threads 2 -o " + (dir / "b.vdb"), &out), 0) << out;
  EXPECT_EQ(testutil::read_text(dir / "a.vdb"), testutil::read_text(dir / "b.vdb"));
  ASSERT_EQ(run_cli("info " + (dir / "a.vdb"), &out), 0) << out;
  EXPECT_NE(out.find("view"), std::string::npos) << out;
  const std::string saved = testutil::read_text(dir / "ring.json");
  EXPECT_NE(saved.find("\"file\": \"ring.obj\""), std::string::npos) << saved;
  EXPECT_EQ(run_cli("shape " + (dir / "ring.obj") + " -o " + (dir / "c.vdb") + " --style lumpy", &out), 1);
  EXPECT_NE(out.find("expected smooth | billowy | wispy"), std::string::npos) << out;
  EXPECT_EQ(run_cli("shape " + (dir / "ring.obj") + " -o " + (dir / "c.vdb") + " --size 800 --voxel-size 0.01", &out), 1);
  EXPECT_NE(out.find("--voxel-size 0.01"), std::string::npos) << out;
  EXPECT_EQ(run_cli("shape " + (dir / "ring.obj") + " -o " + (dir / "ring.obj") + " --format vdb", &out), 1) << out;
  EXPECT_NE(out.find("would overwrite the preset's mesh"), std::string::npos) << out;
  EXPECT_EQ(testutil::read_text(dir / "ring.obj"), sphere_obj(0, 0, 0, 1, 10, 20));
  EXPECT_FALSE(std::filesystem::exists(dir / "c.vdb"));
}

// VDB sources: a fog volume cloudgen wrote (z-up, found from its transform) cut at iso, and a level
// set from OpenVDB's own Python binding (y-up), each put cloud inside the sphere they hold; skipping
// stays exact; bad grids are refused naming the file's grids.
TEST(VdbSource, FogAndLevelSetPutCloudInsideTheirSurface) {
  TempDir dir;
  auto sphere = [](double r) {
    return [r](double x, double y, double z) { return std::hypot(x - 320, y - 300, z - 330) < r; };
  };
  // 1. A cloudgen fog volume: the neutral sphere of radius 170 (density (s - 0.5) / 0.5, so 0.05 lies
  //    1.7 m inside the sphere's surface with falloff 100).
  testutil::write_text(dir / "fog.json", R"({"resolution": [64, 64, 64], "voxel_size": 10, "tiling": false,
      "threshold": 0.5, "channels": {"r": {"remap": [-1, -0.5]}},
      "shape": {"falloff": 100, "sources": [{"kind": "sphere", "center": [320, 300, 330], "radius": 170}]}})");
  std::string out;
  ASSERT_EQ(run_cli("generate " + (dir / "fog.json") + " -q -o " + (dir / "fog.vdb"), &out), 0) << out;
  const Preset fog = meshed(R"({"falloff": 100, "sources": [{"kind": "vdb", "file": ")" + (dir / "fog.vdb") + R"(", "iso": 0.05}]})", true);
  ASSERT_TRUE(fog.shape.sources[0].vdb);
  EXPECT_EQ(fog.shape.sources[0].vdb->up, 'z');
  EXPECT_FALSE(fog.shape.sources[0].vdb->level_set);
  const double a = iou(generate(fog), sphere(168));
  // 2. A level set sphere of radius 150 from pyopenvdb (y up, 5 m voxels).
  const int py = testutil::run_shell("/usr/bin/python3 -c \"import pyopenvdb as v; g = v.createLevelSetSphere(150, (320, 300, 330), 5, 3); "
                                     "g.name = 'surface'; v.write('" + (dir / "ls.vdb") + "', grids=[g])\" 2>&1", &out);
  double b = 1;
  if (py == 0) {
    const Preset ls = meshed(R"({"falloff": 100, "sources": [{"kind": "vdb", "file": ")" + (dir / "ls.vdb") + R"(", "grid": "surface"}]})", true);
    EXPECT_TRUE(ls.shape.sources[0].vdb->level_set);
    b = iou(generate(ls), sphere(150));
    // Skipping exact, with the noise eroding.
    const Preset eroded = meshed(R"({"falloff": 100, "sources": [{"kind": "vdb", "file": ")" + (dir / "ls.vdb") + R"("}]})", false);
    GenerateOptions on, off;
    off.skip_empty = false;
    GenerateStats st;
    EXPECT_TRUE(same_bytes(generate(eroded, on, &st).density, generate(eroded, off).density));
    EXPECT_GT(st.bricks_skipped, 0u);
  } else {
    std::printf("  no python3-openvdb: the level set half skipped (%s)\n", out.c_str());
  }
  std::printf("  IoU %.4f (cloudgen fog at iso 0.05), %.4f (pyopenvdb level set)\n", a, b);
  EXPECT_GE(a, 0.97);
  EXPECT_GE(b, 0.97);
  // Bad grids and keys.
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"sources": [{"kind": "vdb", "file": ")" + (dir / "fog.vdb") + R"(", "grid": "nope"}]}})")
                .find("no grid \"nope\" (the file's grids: density"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"sources": [{"kind": "vdb", "file": ")" + (dir / "fog.vdb") + R"(", "iso": 2}]}})")
                .find("never exceeds iso 2"),
            std::string::npos);
  testutil::write_text(dir / "cube.obj", box_obj(0, 0, 0, 1, 1, 1));
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"sources": [{"kind": "mesh", "file": ")" + (dir / "cube.obj") + R"(", "grid": "x"}]}})")
                .find("/shape/sources/0/grid: is not a key of a mesh (only of a vdb source)"),
            std::string::npos);
}
