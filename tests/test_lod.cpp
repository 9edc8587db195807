// Levels of detail (issue 46, item 1): the viewer draws the coarsest level of a .vdb written with
// `cloudgen generate --lod` whose voxel stays about a pixel on screen (render.lod_bias moves that
// by powers of two) and that fits render.dense_budget, says which, and a coarse level lights like
// the full resolution it stands for.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudviewer/cpu_renderer.h"
#include "cloudviewer/input.h"
#include "cloudviewer/lod.h"
#include "test_util_viewer.h"

using namespace cloudviewer;

namespace {

using testutil::kPresets;
using testutil::TempDir;

/// cumulus-field at 128 voxels across (200 m voxels) with 3 levels of detail.
struct LodFileFixture {
  TempDir dir;
  std::string path = dir / "field.vdb";
  LodFileFixture() {
    cloudgen::Preset p = cloudgen::load_preset(kPresets + "cumulus-field.json");
    cloudgen::rescale(p, 128);
    cloudgen::ExportOptions o = p.export_options;
    o.vdb_lod = 3;
    cloudgen::write_vdb(cloudgen::generate(p), path, o);
  }
};

const LodFileFixture& field() {
  static const LodFileFixture f;
  return f;
}

LodFile facts(const std::string& path) {
  return lod_file_of(cloudgen::read_scene_info(path));
}

/// Looking at the box's centre along +z from `d` metres before its near face, at its mid height.
Camera camera_before(const LodFile& f, double d) {
  Camera c;
  const glm::dvec3 centre = f.box_min + 0.5 * f.box_size;
  c.eye = glm::dvec3(centre.x, centre.y, f.box_min.z - d);
  c.target = centre;
  return c;
}

}  // namespace

// The choice itself: coarser with distance, one level per unit of render.lod_bias, level 0 inside
// the box, coarser again when a level exceeds the dense budget, never beyond the file's levels.
TEST(Lod, ChoiceFollowsTheVoxelsScreenSizeTheBiasAndTheBudget) {
  const LodFile f = facts(field().path);
  ASSERT_EQ(f.levels, 3u);
  EXPECT_DOUBLE_EQ(f.voxel_size, 200.0);
  RenderSettings s = testutil::with({"render.dense_budget=100000"});
  uint32_t last = 0;
  for (double d : {100.0, 1e4, 3e4, 1e5, 3e5, 1e6}) {
    const LodPick p = choose_lod(f, camera_before(f, d), 90, s);
    EXPECT_GE(p.level, last) << "a farther camera never draws finer (" << d << " m)";
    EXPECT_LE(p.level, f.levels);
    // The level's voxel is at most a pixel, and the next coarser one's more (unless clamped).
    if (p.level > 0) {
      EXPECT_LE(p.voxel_pixels * double(1u << p.level), 1.0) << d;
    }
    if (p.level < f.levels) {
      EXPECT_GT(p.voxel_pixels * double(2u << p.level), 1.0) << d;
    }
    last = p.level;
  }
  EXPECT_EQ(last, f.levels) << "a million metres away: the coarsest level";
  Camera inside;
  inside.eye = f.box_min + 0.5 * f.box_size;
  inside.target = inside.eye + glm::dvec3(0, 0, 1);
  EXPECT_EQ(choose_lod(f, inside, 90, s).level, 0u);
  const Camera mid = camera_before(f, 1e5);  // 200 m voxels at 0.16 px: level 2
  const uint32_t base = choose_lod(f, mid, 90, s).level;
  ASSERT_GT(base, 0u);
  ASSERT_LT(base, f.levels);
  EXPECT_EQ(choose_lod(f, mid, 90, testutil::with({"render.dense_budget=100000", "render.lod_bias=1"})).level, base + 1);
  EXPECT_EQ(choose_lod(f, mid, 90, testutil::with({"render.dense_budget=100000", "render.lod_bias=-1"})).level, base - 1);
  EXPECT_EQ(choose_lod(f, mid, 90, testutil::with({"render.dense_budget=100000", "render.lod_bias=-16"})).level, 0u);
  // Level 0 is 128x~19x128 voxels (about 5 MiB dense); a 1 MiB budget skips to a level that fits.
  const LodPick tight = choose_lod(f, camera_before(f, 100.0), 90, testutil::with({"render.dense_budget=1"}));
  EXPECT_TRUE(tight.by_memory);
  EXPECT_GT(tight.level, 0u);
  const std::array<uint32_t, 3> d = lod_dims(f.dims, tight.level);
  EXPECT_LE(prepared_bytes(uint64_t(d[0]) * d[1] * d[2]), uint64_t(1) << 20);
  // render.volume=nanovdb has no dense copy: the budget does not apply.
  EXPECT_FALSE(choose_lod(f, camera_before(f, 100.0), 90,
                          testutil::with({"render.dense_budget=1", "render.volume=nanovdb"})).by_memory);
}

// The program: rendered headless at 160x90, the file's default view draws level 0; from far away
// a coarser level, which the printed line names; render.lod_bias changes the pick.
TEST(Lod, HeadlessRenderFromFarPicksACoarserLevelAndSaysWhich) {
  TempDir out_dir;
  auto pick = [&](std::vector<std::string> extra) {
    std::vector<std::string> args{field().path, "--headless", "--backend", "cpu", "--size", "160x90",
                                  "--out", out_dir / "f.png"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::string err, out;
    EXPECT_EQ(testutil::run(args, &err, &out), 0) << err << out;
    const size_t at = out.find("level of detail ");
    EXPECT_NE(at, std::string::npos) << out;
    return at == std::string::npos ? -1 : std::stoi(out.substr(at + 16));
  };
  EXPECT_EQ(pick({}), 0) << "the default framing shows 200 m voxels at about 2 px";
  const std::string far = "0,2000,-60000:12800,2000,12800";
  const int coarse = pick({"--camera", far});
  EXPECT_GE(coarse, 1) << "60 km away a 200 m voxel is a quarter of a pixel";
  EXPECT_EQ(pick({"--camera", far, "--set", "render.lod_bias=1"}), coarse + 1);
  EXPECT_EQ(pick({"--camera", far, "--set", "render.lod_bias=-4"}), 0);
}

// A coarse level stands for the same cloud: the same extinction per metre (render.sigma_t pinned to
// the full resolution's; left to follow the voxel size it would halve and thin the cloud), so from
// where the choice picks it the cloud's opacity over the picture (1 - mean transmittance) stays
// near level 0's. Not equal: the level keeps the density's integral, and spreading an opaque core
// over a larger voxel makes it more opaque (1 - exp(-x) is concave); measured +15% here.
TEST(Lod, ACoarseLevelFromFarLooksLikeTheFullResolution) {
  const LodFile f = facts(field().path);
  const RenderSettings s = testutil::with({"render.dense_budget=100000", "render.output=transmittance"});
  Camera cam;  // from above, where the field covers much of the picture
  cam.target = f.box_min + 0.5 * f.box_size;
  cam.eye = cam.target + glm::dvec3(0.0, 45e3, -10e3);  // 200 m voxels at about 0.35 px: level 1
  const uint32_t level = choose_lod(f, cam, 90, s).level;
  ASSERT_GT(level, 0u);
  auto opacity = [&](uint32_t l, double sigma_t) {
    RenderSettings r = s;
    r.sigma_t = sigma_t;
    const PreparedVolume vol = open_input(field().path, r, l);
    EXPECT_DOUBLE_EQ(vol.voxel_size, f.voxel_size * double(1u << l));
    const FrameSetup fr = make_frame(vol, r, cam, default_sun(cam), 160, 90);
    return 1.0 - image_stats(render_cpu(vol, fr).linear).mean;
  };
  const double pinned = cloudgen::default_extinction_per_metre(f.voxel_size);
  const double o0 = opacity(0, pinned), ol = opacity(level, pinned), unpinned = opacity(level, 0);
  std::printf("  cloud opacity over the picture: level 0 %.5f, level %u %.5f (%.5f with its own voxel's default extinction)\n",
              o0, level, ol, unpinned);
  ASSERT_GT(o0, 0.002) << "the cloud must cover part of the picture";
  EXPECT_NEAR(ol / o0, 1.0, 0.2);
  EXPECT_GE(ol, o0) << "averaging opaque cores into larger voxels never thins the picture";
  EXPECT_LT(unpinned, o0) << "the coarse voxel's own default extinction would";
}
