// The viewer's default view (issue 12): the preset/metadata view wins over defaults and loses to
// flags, a bare volume is framed from 30 degrees above so it fills the frame, up=z and up=y VDBs
// give the same picture, and the constants `cloudgen blender` copies are the viewer's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "../viewer/src/scene/default_view.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudgen/schema.h"
#include "cloudgen/view.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util.h"

using namespace cloudviewer;
namespace fs = std::filesystem;

namespace {
using testutil::kPresets;
using testutil::TempDir;
}  // namespace

// Issue 47, D20: `generate tiny --set 'view.render={"steps":1e9}' -o vr.vdb` wrote a file that
// cloudviewer then refused. The preset reader checks view.render with the viewer's own table
// (cloudviewer_params): every render.* key just beyond its range is refused, naming the preset,
// the field, the value and the range, and at the end of its range accepted; `generate` writes
// nothing and `validate` says the same; a file generated with an accepted view opens in the viewer.
TEST(DefaultView, GenerateAndValidateRefuseAViewTheViewerWouldRefuse) {
  int refused = 0;
  for (const ParamDef& d : render_params()) {
    SCOPED_TRACE(d.key);
    std::string beyond, at_end;
    switch (d.kind) {
      case ParamKind::Bool: beyond = "\"maybe\"", at_end = "true"; break;
      case ParamKind::Enum: beyond = "\"nonsense\"", at_end = "\"" + d.choices.back() + "\""; break;
      default: beyond = cloudgen::shortest_text(d.hi + std::max(1.0, std::abs(d.hi))), at_end = cloudgen::shortest_text(d.hi);
    }
    const std::string doc = R"({"resolution": [8, 8, 8], "view": {"render": {")" + d.key + "\": ";
    try {
      cloudgen::parse_preset(doc + beyond + "}}}", "p.json");
      ADD_FAILURE() << d.key << "=" << beyond << " accepted";
    } catch (const cloudgen::InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("p.json: /view/render/" + d.key + ": "), std::string::npos) << m;
      EXPECT_NE(m.find("is refused by cloudviewer's table"), std::string::npos) << m;
      ++refused;
    }
    EXPECT_NO_THROW(cloudgen::parse_preset(doc + at_end + "}}}", "p.json")) << d.key << "=" << at_end;
  }
  EXPECT_EQ(refused, int(render_params().size()));

  TempDir dir;
  std::string out;
  const std::string set = " --set 'view.render={\"steps\":1e9}'";
  EXPECT_EQ(testutil::run_cli("generate tiny -q" + set + " -o " + dir / "vr.vdb", &out), 1) << out;
  for (const char* part : {"tiny.json: /view/render/steps: 1000000000.0 is refused by cloudviewer's table",
                           "allowed: a number in [1, 8192]"})
    EXPECT_NE(out.find(part), std::string::npos) << out;
  EXPECT_TRUE(testutil::list_dir(dir.path).empty()) << "nothing written";
  EXPECT_EQ(testutil::run_cli("validate tiny" + set, &out), 1) << out;
  EXPECT_NE(out.find("/view/render/steps: 1000000000.0"), std::string::npos) << out;
  // Accepted by generate: opened by the viewer, with the view's value.
  ASSERT_EQ(testutil::run_cli("generate tiny -q --set 'view.render={\"steps\":8192}' -o " + dir / "ok.vdb", &out), 0) << out;
  Options o;
  o.input = dir / "ok.vdb";
  apply_input_view(o, false);
  EXPECT_EQ(o.settings.steps, 8192);
}

TEST(DefaultView, LookDefaultsAndConstantsAreTheViewers) {
  const RenderSettings s;
  const cloudgen::Look l;
  EXPECT_EQ(s.sigma_t, l.sigma_t);
  EXPECT_EQ(s.density, l.density);
  EXPECT_EQ(s.erosion, l.erosion);
  EXPECT_EQ(s.albedo, l.albedo);
  EXPECT_EQ(s.g, l.g);
  EXPECT_EQ(s.sun_intensity, l.sun_intensity);
  EXPECT_EQ(s.ambient, l.ambient);
  EXPECT_EQ(s.exposure, l.exposure);
  EXPECT_EQ(s.ground, l.ground);
  EXPECT_EQ(s.ground_albedo, l.ground_albedo);
  EXPECT_EQ(s.phase, PhaseMode::HenyeyGreenstein);
  EXPECT_EQ(l.phase, "hg");
  EXPECT_EQ(s.tonemap, ToneMap::Reinhard);
  EXPECT_EQ(l.tonemap, "reinhard");
  const PreparedVolume vol = prepare_volume(synthetic_volume("blob"), 8);
  const Camera cam = default_camera(vol, 60, 16.0 / 9);
  // The scene's constant sun and ambient colours are the analytic sky's (the precomputed
  // atmosphere, the viewer's default since the sky issue, colours both per sample).
  RenderSettings analytic = s;
  apply_setting(analytic, "sky=analytic");
  const FrameSetup f = make_frame(vol, analytic, cam, default_sun(cam), 32, 18);
  for (int i = 0; i < 3; ++i) {
    EXPECT_FLOAT_EQ(float(f.params.sun_color[i]), float(cloudgen::kSunColor[size_t(i)])) << i;
    EXPECT_FLOAT_EQ(float(f.params.ambient_color[i]), float(cloudgen::kAmbientColor[size_t(i)])) << i;
    EXPECT_FLOAT_EQ(float(f.params.sky_zenith[i]), float(cloudgen::kSkyZenith[size_t(i)])) << i;
  }
  EXPECT_FLOAT_EQ(float(f.params.sigma_t_per_m), float(cloudgen::default_extinction_per_metre(vol.voxel_size)));
  EXPECT_DOUBLE_EQ(default_sun(cam).elevation_deg, cloudgen::kDefaultSunElevation);
  const glm::dvec3 want = Sun{30, 20}.direction();
  EXPECT_NEAR(glm::length(glm::dvec3(cloudgen::sun_direction(30, 20)[0], cloudgen::sun_direction(30, 20)[1],
                                     cloudgen::sun_direction(30, 20)[2]) - want), 0.0, 1e-12);
}

TEST(DefaultView, BareLayerFillsTheFrameFromThirtyDegreesAbove) {
  // Today's complaint: a 6 km x 0.9 km layer at 4.2 km opened as a thin line on the horizon.
  cloudgen::Volume v;
  v.dims = {120, 18, 60};
  v.voxel_size = 50;
  v.origin = {-3000, 4200, -1500};
  v.density.assign(v.voxel_count(), 0.5f);
  const PreparedVolume vol = prepare_volume(v, 8);
  const int w = 128, h = 72;
  const Camera cam = default_view_camera(vol, RenderSettings{}, 60, double(w) / h);
  const glm::dvec3 dir = glm::normalize(cam.target - cam.eye);
  EXPECT_NEAR(glm::degrees(std::asin(-dir.y)), 30.0, 1e-9);
  EXPECT_NEAR(std::abs(dir.x), 0.0, 1e-12) << "looks across the short side (z), the 6 km side faces the camera";
  const glm::dmat4 vp = view_projection(cam, w, h);
  double most = 0;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 c = vol.origin + glm::dvec3(i & 1, (i >> 1) & 1, (i >> 2) & 1) * vol.size();
    glm::dvec4 clip = vp * glm::dvec4(c - cam.eye, 1.0);
    ASSERT_GT(clip.w, 0);
    const double nx = clip.x / clip.w, ny = clip.y / clip.w;
    EXPECT_LE(std::abs(nx), 1.0) << i;
    EXPECT_LE(std::abs(ny), 1.0) << i;
    most = std::max({most, std::abs(nx), std::abs(ny)});
  }
  EXPECT_GT(most, 0.85) << "the box fills the frame";
}

TEST(DefaultView, UpZAndUpYFilesGiveTheSamePicture) {
  TempDir dir;
  cloudgen::Volume v = cloudgen::generate_from_file(kPresets + "tiny.json");
  for (char up : {'z', 'y'}) {
    cloudgen::ExportOptions o;
    o.vdb_up = up;
    cloudgen::write_vdb(v, dir / std::string(1, up) + ".vdb", o);
  }
  Image img[2];
  for (int i = 0; i < 2; ++i) {
    Options o;
    o.input = dir / (i ? "y.vdb" : "z.vdb");
    apply_input_view(o, false);
    const PreparedVolume vol = prepare_volume(load_volume(o.input), 8);
    const Camera cam = default_view_camera(vol, o.settings, o.fov, 48.0 / 27);
    img[i] = render_cpu(vol, make_frame(vol, o.settings, cam, default_view_sun(o, cam), 48, 27)).linear;
  }
  ASSERT_EQ(img[0].rgba.size(), img[1].rgba.size());
  EXPECT_EQ(rmse(img[0], img[1]), 0.0);
  EXPECT_GT(image_stats(img[0]).stddev, 0.01) << "not blank";
}

TEST(DefaultView, TheFilesViewWinsOverDefaultsAndLosesToFlags) {
  TempDir dir;
  const cloudgen::Preset p = cloudgen::load_preset(
      kPresets + "tiny.json", {"view.eye=[400,900,-1500]", "view.target=[400,300,400]", "view.fov=35",
                               "view.sun.elevation=50", "view.render.g=0.55", "view.render.exposure=2"});
  cloudgen::Volume v = cloudgen::generate(p);
  cloudgen::add_view_metadata(v.metadata, p.view);
  cloudgen::write_vdb(v, dir / "t.vdb", {});
  Options o;
  o.input = dir / "t.vdb";
  o.sets = {"render.exposure=3"};
  apply_input_view(o, false);
  ASSERT_TRUE(o.camera);
  EXPECT_EQ(o.camera->eye, glm::dvec3(400, 900, -1500));
  EXPECT_EQ(o.camera->target, glm::dvec3(400, 300, 400));
  EXPECT_EQ(o.fov, 35.0);
  EXPECT_EQ(o.settings.g, 0.55);
  EXPECT_EQ(o.settings.exposure, 3.0) << "--set beats the view";
  const Sun s = default_view_sun(o, *o.camera);
  EXPECT_EQ(s.elevation_deg, 50.0);
  EXPECT_EQ(s.azimuth_deg, default_sun(*o.camera).azimuth_deg) << "azimuth not in the view: behind the camera";
  // The preset file itself gives the same view.
  Options q;
  q.input = dir / "p.json";
  {
    std::ofstream(q.input) << R"({"name": "t", "resolution": [8, 8, 8], "view": {"fov": 20, "render": {"g": 0.7}}})";
  }
  apply_input_view(q, true);
  EXPECT_EQ(q.fov, 60.0) << "--fov given";
  EXPECT_EQ(q.settings.g, 0.7);
  EXPECT_FALSE(q.camera);
  // A bad render key names the input: in a preset, the preset reader refuses it (the viewer's
  // table, GenerateAndValidateRefuseAViewTheViewerWouldRefuse); in a file's metadata (another
  // writer's), the viewer does.
  try {
    cloudgen::parse_preset(R"({"resolution": [8, 8, 8], "view": {"render": {"gg": 1}}})", "b.json");
    FAIL() << "no error";
  } catch (const cloudgen::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("b.json: /view/render/gg: 1 is refused by cloudviewer's table: unknown key render.gg"),
              std::string::npos) << e.what();
  }
  cloudgen::View bad;
  bad.render = {{"gg", "1"}};
  cloudgen::add_view_metadata(v.metadata, bad);
  cloudgen::write_vdb(v, dir / "b.vdb", {});
  Options b;
  b.input = dir / "b.vdb";
  try {
    apply_input_view(b, false);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("b.vdb: view.render.gg"), std::string::npos) << e.what();
  }
}

// Every shipped preset opens in its own view: the view's render keys are ones its volume takes
// (render.mode=layer needs a volume that tiles, or make_frame refuses it and the preset cannot be
// shown), and the picture is not blank. At a reduced resolution, which keeps the preset's tiling.
TEST(DefaultView, EveryShippedPresetOpensInItsOwnView) {
  int shipped = 0, layers = 0;
  for (const auto& e : fs::directory_iterator(kPresets)) {
    if (e.path().extension() != ".json") continue;
    ++shipped;
    SCOPED_TRACE(e.path().filename().string());
    const cloudgen::Preset p = cloudgen::load_preset(e.path().string(), {"resolution=[32,16,32]"});
    const PreparedVolume vol = prepare_volume(cloudgen::generate(p), 8);
    Options o;
    o.input = e.path();
    apply_input_view(o, false);
    const Camera cam = o.camera ? *o.camera : default_view_camera(vol, o.settings, o.fov, 48.0 / 27);
    FrameSetup f;
    ASSERT_NO_THROW(f = make_frame(vol, o.settings, cam, default_view_sun(o, cam), 48, 27));
    if (o.settings.mode == PlaceMode::Layer) {
      ++layers;
      EXPECT_TRUE(vol.tiles);
      EXPECT_LT(cam.eye.y, layer_altitudes(vol, o.settings).x) << "the layer's default view is from the ground";
    }
    EXPECT_GT(image_stats(render_cpu(vol, f).display).stddev, 0.02) << "not blank";
  }
  EXPECT_GE(shipped, 6);
  EXPECT_GE(layers, 1) << "stratus is shown as the layer it is";
}
