// Blender-ready export: the VDB's up axis and placement (OpenVDB's voxel-centre convention), the
// physical metadata, the detail grids' topology, every field read back, and the preset `view`.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "cloudgen/erosion.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudgen/view.h"
#include "test_util.h"

using namespace cloudgen;
namespace fs = std::filesystem;

namespace {

using testutil::kPresets;
using testutil::same_bytes;
using testutil::TempDir;

[[maybe_unused]] std::string meta(const Volume& v, const std::string& key) {
  for (auto& [k, val] : v.metadata)
    if (k == key) return val;
  return "";
}

Volume one_voxel() {
  Volume v;
  v.dims = {1, 1, 1};
  v.voxel_size = 10;
  v.origin = {100, 200, 300};
  v.density = {1.0f};
  return v;
}

}  // namespace

TEST(BlenderExport, UpZAndUpYReadBackToTheSameVolume) {
  TempDir dir;
  Volume v = generate(load_preset(kPresets + "tiny.json"));
  ASSERT_TRUE(v.tiles_xz);
  Volume r[2];
  for (int i = 0; i < 2; ++i) {
    ExportOptions o;
    o.vdb_up = i ? 'y' : 'z';
    write_vdb(v, dir / (i ? "y.vdb" : "z.vdb"), o);
    r[i] = read_vdb(dir / (i ? "y.vdb" : "z.vdb"));
    EXPECT_TRUE(r[i].tiles_xz) << "tiles_xz survives the VDB (issue 7: readers keep every field)";
    const SceneInfo s = read_scene_info(dir / (i ? "y.vdb" : "z.vdb"));
    EXPECT_EQ(s.up, o.vdb_up);
    EXPECT_EQ(s.dims, r[i].dims);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.origin[a], r[i].origin[a], 1e-9);
  }
  EXPECT_EQ(r[0].dims, r[1].dims);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(r[0].origin[a], r[1].origin[a], 1e-9) << a;
  EXPECT_TRUE(same_bytes(r[0].density, r[1].density));
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bytes(r[0].detail[c], r[1].detail[c])) << c;
  EXPECT_NE(describe_vdb(dir / "z.vdb").find("up axis: z"), std::string::npos);
  EXPECT_NE(describe_vdb(dir / "y.vdb").find("up axis: y"), std::string::npos);
}

TEST(BlenderExport, OneVoxelLandsAtItsCentreInBothFrames) {
  // OpenVDB's convention: voxel (0,0,0)'s value sits at index point (0,0,0), which the transform
  // maps to the voxel's centre origin + 0.5 voxel. tests/blender_roundtrip.sh checks the same file
  // layout with OpenVDB's own indexToWorld; here the reader and the info text.
  TempDir dir;
  Volume v = one_voxel();
  v.voxel_size = 50;  // OpenVDB's own hasUniformVoxels() rejects a turned 50 m map
  v.origin = {100, 200, 300};
  for (char up : {'y', 'z'}) {
    ExportOptions o;
    o.vdb_up = up;
    const std::string path = dir / std::string(1, up) + ".vdb";
    write_vdb(v, path, o);
    const Volume r = read_vdb(path);
    ASSERT_EQ(r.dims, v.dims);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.origin[a], v.origin[a], 1e-9) << up << a;
    // The world box of the voxel: y-up [100,150]x[200,250]x[300,350]; z-up (x, -z, y).
    const std::string want = up == 'y' ? "world bbox [100, 200, 300] .. [150, 250, 350]"
                                       : "world bbox [100, -350, 200] .. [150, -300, 250]";
    EXPECT_NE(describe_vdb(path).find(want), std::string::npos) << describe_vdb(path);
  }
}

TEST(BlenderExport, DetailGridsCoverTheDensityDilatedByOneVoxelExactly) {
  TempDir dir;
  Volume v = generate(load_preset(kPresets + "tiny.json"));
  ExportOptions keep;
  keep.vdb_bake_erosion = false;  // the detail grids (the default bakes the erosion instead)
  write_vdb(v, dir / "t.vdb", keep);
  // Read back without cropping: a volume whose density is 1 in the corner voxels keeps the box.
  const Volume r = read_vdb(dir / "t.vdb");
  const int oy = int(std::lround((r.origin[1] - v.origin[1]) / v.voxel_size));
  ASSERT_EQ(r.dims[0], v.dims[0]);
  ASSERT_EQ(r.dims[2], v.dims[2]);
  const int nx = int(v.dims[0]), ny = int(v.dims[1]), nz = int(v.dims[2]);
  auto dens = [&](int x, int y, int z) {
    x = (x % nx + nx) % nx, z = (z % nz + nz) % nz;  // tiny tiles in x and z
    return y < 0 || y >= ny ? 0.f : v.density[v.index(uint32_t(x), uint32_t(y), uint32_t(z))];
  };
  size_t kept = 0, dropped = 0;
  for (int z = 0; z < int(r.dims[2]); ++z)
    for (int y = 0; y < int(r.dims[1]); ++y)
      for (int x = 0; x < int(r.dims[0]); ++x) {
        bool near = false;
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) near |= dens(x + dx, y + oy + dy, z + dz) > 0;
        const float got = r.detail[0][r.index(uint32_t(x), uint32_t(y), uint32_t(z))];
        const float want = v.detail[0][v.index(uint32_t(x), uint32_t(y + oy), uint32_t(z))];
        if (near) {
          ASSERT_EQ(got, want) << x << "," << y << "," << z << ": a trilinear read of density > 0 needs this voxel";
          ++kept;
        } else {
          ASSERT_EQ(got, 0.f) << x << "," << y << "," << z;
          ++dropped;
        }
      }
  EXPECT_GT(kept, 0u);
  EXPECT_GT(dropped, 0u) << "detail beyond one voxel of the cloud is not stored";
}

TEST(BlenderExport, PhysicalMetadataAndUnits) {
  TempDir dir;
  Volume v = generate(load_preset(kPresets + "tiny.json"));
  write_vdb(v, dir / "n.vdb", {});
  std::string info = describe_vdb(dir / "n.vdb");
  std::ostringstream want;
  want << "extinction_per_metre: " << default_extinction_per_metre(v.voxel_size);
  EXPECT_NE(info.find(want.str()), std::string::npos) << info;
  EXPECT_NE(info.find("voxel_size_metres: 25"), std::string::npos) << info;
  EXPECT_NE(info.find("phase_g: 0.3"), std::string::npos) << info;
  EXPECT_NE(info.find("density_units: normalized"), std::string::npos) << info;

  // A view's render.sigma_t and density multiplier set the extinction; physical units store it.
  View view;
  view.render = {{"sigma_t", "0.02"}, {"density", "2"}, {"g", "0.6"}};
  add_view_metadata(v.metadata, view);
  ExportOptions o;
  o.vdb_physical = true;
  write_vdb(v, dir / "p.vdb", o);
  info = describe_vdb(dir / "p.vdb");
  EXPECT_NE(info.find("extinction_per_metre: 0.04"), std::string::npos) << info;
  EXPECT_NE(info.find("phase_g: 0.6"), std::string::npos) << info;
  EXPECT_NE(info.find("density_units: extinction_per_metre"), std::string::npos) << info;
  EXPECT_NE(info.find("values min"), std::string::npos);
  const Volume r = read_vdb(dir / "p.vdb");
  const Volume n = read_vdb(dir / "n.vdb");
  ASSERT_EQ(r.density.size(), n.density.size());
  double maxerr = 0;
  for (size_t i = 0; i < r.density.size(); ++i) maxerr = std::max(maxerr, double(std::fabs(r.density[i] - n.density[i])));
  EXPECT_LE(maxerr, 1e-6) << "the reader turns extinction back into normalised density";
  EXPECT_EQ(view_to_json(view_of_metadata(r.metadata, "p.vdb")), view_to_json(view));
}

TEST(BlenderExport, PresetViewSectionThroughTheTable) {
  const Preset p = parse_preset(R"({"name": "t", "resolution": [8, 8, 8]})", "t.json",
                                {"view.eye=[1,2,3]", "view.fov=40", "view.sun.azimuth=-30", "view.render.g=0.5",
                                 "export.vdb.up=y"});
  ASSERT_TRUE(p.view.eye && p.view.fov && p.view.sun_azimuth);
  EXPECT_EQ((*p.view.eye)[2], 3.0);
  EXPECT_FALSE(p.view.target) << "unset keys stay unset (the viewer's default)";
  EXPECT_EQ(*p.view.fov, 40.0);
  ASSERT_EQ(p.view.render.size(), 1u);
  EXPECT_EQ(p.view.render[0].first, "g");
  EXPECT_EQ(look_of_view(p.view, "x").g, 0.5);
  EXPECT_EQ(p.export_options.vdb_up, 'y');
  EXPECT_EQ(load_preset(kPresets + "tiny.json").export_options.vdb_up, 'z') << "Blender is the main target";
  const View back = view_from_json(view_to_json(p.view), "x");
  EXPECT_EQ(view_to_json(back), view_to_json(p.view));
  auto error = [](std::vector<std::string> sets) {
    try {
      load_preset(kPresets + "tiny.json", sets);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error({"view.fov=500"}).find("/view/fov: 500 is out of range"), std::string::npos);
  EXPECT_NE(error({"view.sun.elevation=95"}).find("/view/sun/elevation"), std::string::npos);
  EXPECT_NE(error({"view.eye=[1,2]"}).find("/view/eye"), std::string::npos);
  EXPECT_NE(error({"view.render={\"g\":[1]}"}).find("/view/render/g"), std::string::npos);
  EXPECT_NE(error({"view.camera=1"}).find("unknown key"), std::string::npos);
  EXPECT_NE(error({"export.vdb.up=x"}).find("expected one of: z | y"), std::string::npos);
}

TEST(BlenderExport, FramingFillsTheFrameFromThirtyDegreesAbove) {
  // A 6 km x 0.9 km layer at 4.2 km: the framed box's corners all lie inside the frame and at
  // least one touches its edge (fill 0.92).
  const Vec3 lo{-3000, 4200, -3000}, size{6000, 900, 6000};
  const double fov = 60, aspect = 16.0 / 9;
  const Framing f = frame_box(lo, size, fov, aspect);
  const Vec3 d{f.target[0] - f.eye[0], f.target[1] - f.eye[1], f.target[2] - f.eye[2]};
  const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  EXPECT_NEAR(std::asin(-d[1] / len) * 180 / M_PI, 30.0, 1e-9);
  EXPECT_GT(f.eye[1], lo[1] + size[1]) << "the camera is above the layer";
}

TEST(BlenderExport, BlenderCommandErrorsNameTheProblem) {
  TempDir dir;
  const std::string cli = std::string(CLOUD_BINARY_DIR) + "/bin/cloudgen";
  auto run = [&](const std::string& env, const std::string& args, std::string& out) {
    const std::string cmd = env + " " + cli + " " + args + " 2>&1";
    FILE* p = ::popen(cmd.c_str(), "r");
    char buf[4096];
    out.clear();
    while (size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
    const int st = ::pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  std::string out;
  EXPECT_EQ(run("", "blender tiny -o " + (dir / "x.txt"), out), 1) << out;
  EXPECT_NE(out.find("must end in .blend"), std::string::npos) << out;
  EXPECT_EQ(run("", "blender tiny -o " + (dir / "x.blend") + " --size 0x5", out), 1) << out;
  EXPECT_NE(out.find("--size 0x5"), std::string::npos) << out;
  EXPECT_EQ(run("env PATH=/nonexistent CLOUDGEN_BLENDER=", "blender tiny -o " + (dir / "x.blend"), out), 2) << out;
  EXPECT_NE(out.find("install Debian's package `blender`"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "x.blend"));
  // A "blender" that exits 0 but writes nothing (here /bin/true) is a failure, not a written scene.
  EXPECT_EQ(run("env CLOUDGEN_BLENDER=/bin/true", "blender tiny -o " + (dir / "x.blend") + " --render " + (dir / "x.png"),
                out),
            2)
      << out;
  EXPECT_EQ(out.find("wrote " + (dir / "x.blend")), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "x.blend"));
  EXPECT_FALSE(fs::exists(dir / "x.png"));
  EXPECT_FALSE(fs::exists(dir / "x.vdb")) << "the sibling VDB is in the scene's transaction";
  // Issue 47, D12: a failed Blender leaves an existing sibling OUT.vdb byte for byte.
  testutil::write_text(dir / "y.vdb", "previous contents");
  EXPECT_EQ(run("env CLOUDGEN_BLENDER=/bin/false", "blender tiny -o " + (dir / "y.blend"), out), 2) << out;
  EXPECT_EQ(testutil::read_text(dir / "y.vdb"), "previous contents");
  EXPECT_FALSE(fs::exists(dir / "y.blend"));
  for (const std::string& f : testutil::list_dir(dir.path))
    EXPECT_EQ(f.find(".tmp-"), std::string::npos) << "a temporary was left: " << f;
}

TEST(BlenderExport, BakedErosionReplacesTheDetailGrids) {
  TempDir dir;
  Preset p = load_preset(kPresets + "thesis.json");
  rescale(p, 32);
  const Volume v = generate(p);
  ASSERT_FALSE(v.detail[2].empty());
  ExportOptions o;
  o.vdb_detail = false;
  write_vdb(v, dir / "d.vdb", o);
  o.vdb_detail = true;
  o.vdb_bake_erosion = true;
  write_vdb(v, dir / "b.vdb", o);
  const std::string info = describe_vdb(dir / "b.vdb");
  EXPECT_EQ(info.find("detail_g"), std::string::npos) << info;
  EXPECT_NE(info.find("erosion_baked: 0.35"), std::string::npos) << info;
  EXPECT_LE(fs::file_size(dir / "b.vdb"), fs::file_size(dir / "d.vdb") * 11 / 10) << "about the density grid alone";
  const Volume r = read_vdb(dir / "b.vdb");
  EXPECT_TRUE(r.detail[0].empty());
  // Values: the viewer's erosion at each voxel, the height fraction over the preset's box (the
  // box the viewer measures heights in: the header's motion.box_min_y / motion.box_height).
  double box_min = 0, box_height = 0;
  for (const auto& [k, val] : v.metadata) {
    if (k == "motion.box_min_y") box_min = std::stod(val);
    if (k == "motion.box_height") box_height = std::stod(val);
  }
  ASSERT_GT(box_height, 0) << "the volume header records the preset's box";
  size_t lowered = 0, checked = 0;
  for (uint32_t z = 0; z < r.dims[2]; ++z)
    for (uint32_t y = 0; y < r.dims[1]; ++y)
      for (uint32_t x = 0; x < r.dims[0]; ++x) {
        const uint32_t ox = uint32_t(std::lround((r.origin[0] - v.origin[0]) / v.voxel_size)) + x;
        const uint32_t oy = uint32_t(std::lround((r.origin[1] - v.origin[1]) / v.voxel_size)) + y;
        const uint32_t oz = uint32_t(std::lround((r.origin[2] - v.origin[2]) / v.voxel_size)) + z;
        const size_t i = v.index(ox, oy, oz);
        const double want = eroded_density(v.density[i], v.detail[0][i], v.detail[1][i], v.detail[2][i],
                                           (v.origin[1] + (oy + 0.5) * v.voxel_size - box_min) / box_height, 0.35);
        ASSERT_NEAR(r.density[r.index(x, y, z)], want, 1e-6);
        lowered += want < v.density[i];
        ++checked;
      }
  EXPECT_GT(lowered, checked / 10) << "erosion lowers density";
  // The default export bakes (Blender, which reads density only, is the main target).
  write_vdb(v, dir / "default.vdb", ExportOptions{});
  const std::string dinfo = describe_vdb(dir / "default.vdb");
  EXPECT_EQ(dinfo.find("detail_g"), std::string::npos) << dinfo;
  EXPECT_NE(dinfo.find("erosion_baked: 0.35"), std::string::npos) << dinfo;
  EXPECT_EQ(read_vdb(dir / "default.vdb").density, r.density);
}
