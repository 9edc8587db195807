// The GL renderer's programs (render.compiled_modes, shader_source.h): one program per set of the
// frame's modes gives the image of the run-time switches, a failed compile keeps the old programs,
// and a bench track's keys carry their own settings.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <iostream>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "cloudgen/erosion.h"
#include "cloudviewer/app.h"
#include "cloudviewer/errors.h"

#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util_viewer.h"

using namespace cloudviewer;
using testutil::gl_context;
using testutil::render_gl;
using testutil::with;


namespace {

const int kW = testutil::kFrameW, kH = testutil::kFrameH;
const double kAspect = double(kW) / kH;

}  // namespace

// A track key may carry its own settings (the view from below marches at most 2133 m); a bad one
// is refused before OpenGL, naming the key's JSON pointer.
// render.compiled_modes: the programs compiled for a frame's modes (modes.glsl's macros as
// constants) render what the generic program, reading the modes from the uniform block, renders,
// in each mode the switch bakes in; and a set of modes seen before is not compiled again.
TEST(GlPrograms, CompiledModesKeepTheImage) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("noise"), 8);
  struct Case {
    const char* name;
    std::vector<const char*> sets;
    double time;
  };
  // Each switch of modes.glsl takes a value other than its default in at least one case.
  const std::vector<Case> cases = {
      {"defaults", {}, 0},
      {"layer mode, adaptive, exact filter, iterations output",
       {"render.mode=layer", "render.adaptive=true", "render.steps=48", "render.exact_filter=true", "render.output=iterations"}, 0},
      {"moving clouds, curl distortion, thesis skipping, light skipping",
       {"motion.wind_speed=20", "motion.curl_amplitude=150", "render.skipping=thesis", "render.occupancy_light=true"}, 30},
      {"no skipping, density step, diffusion volume, Mie phase",
       {"render.skipping=none", "render.density_step=2", "render.ms_volume=true", "render.phase=mie"}, 0},
      {"one octave, two lobes, analytic sky, transmittance output",
       {"render.ms_octaves=1", "render.phase=two-lobe-hg", "render.sky=analytic", "render.output=transmittance"}, 0},
      {"ground shadow marched per pixel", {"render.shadow_map=false"}, 0},
      {"no light march, Draine, temporal, marched air",
       {"render.light_march=false", "render.phase=draine-hg", "render.temporal=true", "render.air_lut=false"}, 0},
  };

  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  auto frame = [&](const Case& c, bool compiled) {
    RenderSettings s;
    for (const char* a : c.sets) apply_setting(s, a);
    s.time = c.time;
    s.compiled_modes = compiled;
    Camera cam = default_camera(vol, s, 60, 96.0 / 54);
    return make_frame(vol, s, cam, Sun{200, 30}, 96, 54);
  };
  int after_first = 0;
  FrameImages first;
  // Each frame reports the programs linked since the frame before (the first: the constructor's
  // too) and their compile time: the count is what the cache grew by, and the time is > 0 exactly
  // when something was linked.
  int counted = 0;
  auto render_counting = [&r, &counted](const FrameSetup& f) {
    GpuTimings t;
    r.render(f, &t);
    EXPECT_EQ(t.programs_linked, r.stats().program_count - counted);
    counted = r.stats().program_count;
    EXPECT_EQ(t.compile_ms > 0, t.programs_linked > 0) << t.compile_ms << " ms for " << t.programs_linked;
    return t;
  };
  for (const Case& c : cases) {
    render_counting(frame(c, true));
    FrameImages a = r.read_back();
    if (after_first == 0) first = a;
    render_counting(frame(c, false));
    FrameImages b = r.read_back();
    if (after_first == 0) after_first = r.stats().program_count;
    double scale = std::max(image_stats(b.linear).max, 1e-6);
    double diff = max_abs_diff(a.linear, b.linear) / scale;
    std::cout << c.name << ": compiled vs generic max |diff| / max " << diff << "\n";
    EXPECT_GT(image_stats(b.display).stddev, 0.005) << c.name << ": a picture to compare";
    EXPECT_LE(diff, 1e-6) << c.name;
  }
  // Every case above has its own set of modes: each compiled its own programs...
  const int all = r.stats().program_count;
  EXPECT_GT(all, after_first + 3);
  // ...and going back to the first links nothing new and renders the same picture, bit for bit.
  const GpuTimings again = render_counting(frame(cases[0], true));
  EXPECT_EQ(r.stats().program_count, all);
  EXPECT_EQ(again.programs_linked, 0);
  EXPECT_EQ(again.compile_ms, 0.0);
  EXPECT_EQ(max_abs_diff(first.linear, r.read_back().linear), 0.0);
}

// A set of modes that fails to compile (a file broken under --shader-dir after the renderer
// started) throws, and leaves the renderer with the programs and modes it had: the modes it was
// built for still render the same picture, and the failed set fails again instead of drawing with
// programs compiled for other modes.
TEST(GlPrograms, CompiledModesSurviveAFailedCompile) {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / "cloudviewer_modes_broken";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const std::string& name : embedded_shader_names()) std::ofstream(dir / name) << ShaderSource().load(name);
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  Camera cam = default_camera(vol, 60, 64.0 / 36);
  auto frame = [&](bool exact) {
    RenderSettings s;
    s.exact_filter = exact;
    return make_frame(vol, s, cam, default_sun(cam), 64, 36);
  };
  GlRenderer r{ShaderSource(dir.string())};
  r.set_volume(vol);
  r.render(frame(false));
  FrameImages before = r.read_back();
  std::string text = ShaderSource().load("medium.glsl");
  std::ofstream(dir / "medium.glsl") << text << "\nthis is not glsl;\n";
  EXPECT_THROW(r.render(frame(true)), ShaderError);
  r.render(frame(false));
  EXPECT_EQ(max_abs_diff(before.linear, r.read_back().linear), 0.0);
  EXPECT_THROW(r.render(frame(true)), ShaderError);
  fs::remove_all(dir);
}

TEST(GlPrograms, TrackKeysCarryTheirOwnSettings) {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / "cv_speed_track";
  std::filesystem::create_directories(dir);
  auto track = [&](const std::string& set) {
    std::string path = (dir / "t.json").string();
    std::ofstream(path) << R"({"space": "volume", "keys": [{"name": "a", "eye": [0.5, 0.5, -1], "target": [0.5, 0.5, 0.5],
                          "set": [)" << set << R"(]}], "configs": [{"name": "c", "set": []}]})";
    return path;
  };
  std::ostringstream out, err;
  int code = run_cli({"cloudviewer", "synthetic:sphere", "--headless", "--size", "16x9", "--bench",
                      track("\"render.nope=1\"")}, out, err);
  EXPECT_EQ(code, 1);
  EXPECT_NE(err.str().find("/keys/0/set/0"), std::string::npos) << err.str();
  EXPECT_NE(err.str().find("render.nope"), std::string::npos) << err.str();
  std::ostringstream out2, err2;
  code = run_cli({"cloudviewer", "synthetic:sphere", "--headless", "--size", "16x9", "--bench",
                  track("\"render.max_distance=10\""), "--bench-repeat", "1"}, out2, err2);
  EXPECT_EQ(code, 0) << err2.str();
  // At most 10 m of march: the sphere, 300 m away, is not reached, so no loop trips at all.
  EXPECT_NE(out2.str().find(" 0.0 "), std::string::npos) << out2.str();
  // The bench says what its renderer spent compiling (a fresh renderer links every program).
  const size_t at = out2.str().find("GL programs compiled: ");
  ASSERT_NE(at, std::string::npos) << out2.str();
  EXPECT_GT(std::atoi(out2.str().c_str() + at + 22), 0) << out2.str().substr(at);
  std::filesystem::remove_all(dir);
}
