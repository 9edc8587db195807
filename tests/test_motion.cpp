// Cloud motion (issue 11, seed 003): the shared formula cloudgen/motion.glsl (wind with height
// shear, the two-phase flow map) and the viewer's use of it: the moving volume is the static one
// sampled at displaced positions, occupancy skipping stays exact while the clouds move, time 0 is
// the static image, and --time / --frames / --fps / --out patterns on the command line.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "cloudgen/motion.h"
#include "cloudgen/sequence.h"
#include "cloudviewer/app.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util_viewer.h"

namespace fs = std::filesystem;
using namespace cloudviewer;
using cloudgen::MotionParams;
using cloudgen::motion_displacement;
using testutil::gl_context;
using testutil::read_text;
using testutil::render_gl;
using testutil::run;

namespace {

MotionParams flow_only() {
  MotionParams m;
  m.wind_speed = 0;
  return m;
}

FrameSetup frame_at(const PreparedVolume& vol, RenderSettings s, double t, int w = 160, int h = 90) {
  s.time = t;
  Camera cam = default_camera(vol, 60, double(w) / h);
  return make_frame(vol, s, cam, default_sun(cam), w, h);
}

}  // namespace

// ------------------------------------------------------------------------------ the formula

TEST(MotionFormula, TimeZeroIsTheStaticVolumeExactly) {
  MotionParams m;
  for (int i = 0; i <= 100; ++i) {
    glm::dvec3 d = motion_displacement(m, 0.0, i / 100.0);
    EXPECT_EQ(d.x, 0.0);
    EXPECT_EQ(d.y, 0.0);
    EXPECT_EQ(d.z, 0.0);
  }
}

// The seed's two phases hide each lookup's wrap: stepping across P0 = 0 (t = k / speed) and
// P0 = 0.5 must move the clouds no more than an ordinary frame step does. A one-phase flow map
// would jump by up to the whole amplitude there (hundreds of metres; the frame step is ~0.1 m).
TEST(MotionFormula, FlowOffsetIsContinuousAcrossThePhaseWraps) {
  MotionParams m = flow_only();
  const double period = 1.0 / m.flow_speed, dt = 1.0 / 240.0;
  for (double h : {0.25, 0.6, 1.0}) {
    double ordinary = 0, across = 0;
    for (double t = 0.3 * period; t < 2.3 * period; t += dt) {
      double step = glm::length(motion_displacement(m, t + dt, h) - motion_displacement(m, t, h));
      double ph0 = std::fmod(t / period, 1.0), ph1 = std::fmod((t + dt) / period, 1.0);
      bool wraps = ph1 < ph0 || (ph0 < 0.5 && ph1 >= 0.5);
      (wraps ? across : ordinary) = std::max(wraps ? across : ordinary, step);
    }
    EXPECT_GT(ordinary, 0.0) << "the flow must move at h " << h;
    EXPECT_LE(across, ordinary * 1.01) << "jump at a phase wrap, h " << h;
  }
}

// |flow part| <= 2 x amplitude (a difference of two offsets in [-1, 1]) scaled by h, along up and
// along the wind only; the wind part is speed * t * (1 + shear * h) along its direction.
TEST(MotionFormula, DisplacementIsBoundedAndSplitsIntoWindAndFlow) {
  MotionParams m;
  glm::dvec2 w = cloudgen::motion_glsl::wind_direction_xz(m.wind_direction);
  glm::dvec3 fwd(w.x, 0, w.y);
  for (double t : {0.5, 17.0, 133.3, 1000.0, 86400.0})
    for (int i = 0; i <= 20; ++i) {
      double h = i / 20.0;
      glm::dvec3 d = motion_displacement(m, t, h);
      glm::dvec3 wind = fwd * (m.wind_speed * t * (1 + m.wind_shear * h));
      glm::dvec3 flow = d - wind;
      double tol = 1e-9 * (1 + glm::length(wind));
      EXPECT_LE(std::abs(flow.y), 2 * m.flow_up * h + tol) << "t " << t << " h " << h;
      glm::dvec3 horizontal(flow.x, 0, flow.z);
      EXPECT_LE(glm::length(horizontal), 2 * m.flow_forward * h + tol) << "t " << t << " h " << h;
      EXPECT_NEAR(glm::length(glm::cross(horizontal, fwd)), 0.0, tol) << "flow leaves the wind's plane";
    }
  // h = 0 (the cloud base) only drifts with the wind.
  glm::dvec3 base = motion_displacement(m, 50, 0.0);
  EXPECT_NEAR(glm::length(base - fwd * (m.wind_speed * 50)), 0.0, 1e-9);
}

TEST(MotionFormula, ZeroStrengthMeansNoMotion) {
  MotionParams m;
  m.wind_speed = 0;
  m.flow_up = m.flow_forward = 0;
  EXPECT_FALSE(cloudgen::motion_moves(m));
  for (double t : {0.1, 7.0, 1e4})
    for (double h : {0.0, 0.5, 1.0}) EXPECT_EQ(glm::length(motion_displacement(m, t, h)), 0.0);
  MotionParams f = flow_only();
  f.flow_speed = 0;  // a still flow map and no wind
  EXPECT_FALSE(cloudgen::motion_moves(f));
  for (double t : {0.1, 7.0, 1e4}) EXPECT_EQ(glm::length(motion_displacement(f, t, 0.8)), 0.0);
  EXPECT_TRUE(cloudgen::motion_moves(MotionParams{}));
}

TEST(MotionFormula, DocsTableIsCurrent) {
  std::ifstream in(std::string(CLOUD_SOURCE_DIR) + "/docs/reference/viewer-params.md");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find(cloudgen::motion_markdown()), std::string::npos)
      << "docs/reference/viewer-params.md's motion table is out of date (scripts/gen_docs.sh)";
}

TEST(MotionFormula, TableRejectsBadValuesWithTheRange) {
  MotionParams m;
  cloudgen::set_motion_key(m, "wind_speed", "3.5", "--set");
  EXPECT_EQ(m.wind_speed, 3.5);
  for (const char* bad : {"-1", "nan", "1e9", "fast", ""}) {
    try {
      cloudgen::set_motion_key(m, "wind_speed", bad, "--set");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const cloudgen::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("[0, 200]"), std::string::npos) << e.what();
    }
  }
  try {
    cloudgen::set_motion_key(m, "gusts", "1", "--set");
    ADD_FAILURE();
  } catch (const cloudgen::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("wind_shear"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------------------ the viewer

// The frame's motion table (D at CV_MOTION_LUT_SIZE heights), interpolated linearly at h.
glm::dvec3 table_displacement(const FrameSetup& f, double h) {
  const int n = CV_MOTION_LUT_SIZE;
  double x = std::clamp(h, 0.0, 1.0) * (n - 1);
  int i = std::min(int(std::floor(x)), n - 2);
  return glm::mix(f.motion_table[size_t(i)], f.motion_table[size_t(i + 1)], x - i);
}

// The table the shaders interpolate is motion_displacement to within a centimetre at any height
// (the default flow, strong shear, at several times).
TEST(ViewerMotion, MotionTableFollowsTheFormulaWithinACentimetre) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  RenderSettings s;
  s.motion.wind_shear = 1.5;
  for (double t : {3.0, 95.0, 1000.0}) {
    FrameSetup f = frame_at(vol, s, t);
    ASSERT_EQ(f.motion_table.size(), size_t(2 * CV_MOTION_LUT_SIZE));
    double worst = 0;
    for (int i = 0; i <= 10000; ++i) {
      double h = i / 10000.0;
      worst = std::max(worst, glm::length(table_displacement(f, h) - motion_displacement(s.motion, t, h)));
    }
    EXPECT_LT(worst, 0.01) << "t " << t;
  }
}

// What the viewer sees at p and time t is the static volume at p - D(h(p), t), h the height
// fraction in the box, D from the frame's motion table (the test above bounds it against the
// formula): checked point by point through the CPU reference's cloud_density, for a box cloud
// (zero outside) and a tileable one (x, z wrap).
TEST(ViewerMotion, MovingDensityIsTheStaticDensityAtDisplacedPositions) {
  for (const char* kind : {"blob", "noise"}) {
    PreparedVolume vol = prepare_volume(testutil::synthetic(kind), 8);
    RenderSettings s;
    s.motion.wind_shear = 1.5;
    s.motion.wind_speed = 3.0;  // the grown box stays small enough for random points to find the cloud
    s.erosion = 0;  // its wispy-base rule is taken where a sample is seen (BakedFrame... below covers it)
    const double t = 95.0;
    FrameSetup moving = frame_at(vol, s, t), still = frame_at(vol, s, 0.0);
    ASSERT_EQ(moving.params.motion_on, 1.0);
    ASSERT_EQ(still.params.motion_on, 0.0);
    const glm::dvec3 lo = moving.params.march_min_m, ext = moving.params.march_size_m;
    uint32_t state = 7;
    auto next = [&] { return ((state = state * 1664525u + 1013904223u) >> 8) / double(1u << 24); };
    int nonzero = 0;
    for (int i = 0; i < 8000; ++i) {
      glm::dvec3 p = lo + ext * glm::dvec3(next(), next(), next());
      double h = (p.y - still.params.volume_min_m.y) / still.params.volume_size_m.y;
      glm::dvec3 q = p - table_displacement(moving, h);
      double a = reference_density(vol, moving, p), b = reference_density(vol, still, q);
      EXPECT_NEAR(a, b, 1e-6 * (1 + b)) << kind << " at p (" << p.x << ", " << p.y << ", " << p.z << ")";
      if (b > 0) ++nonzero;
      if (HasFailure()) return;
    }
    EXPECT_GT(nonzero, 100) << kind << ": the samples must reach the cloud";
  }
}

// A frame cloudgen bakes (cloudgen/sequence.h, the VDB sequence) is what the viewer shows of the
// static volume at that time: the viewer's density of the static volume at time t equals its
// density of the baked frame (opened as a still volume) at the frame's voxel centres, for a box
// cloud (whose frame box follows the wind) and a tileable one, erosion included (its wispy-base
// rule is one of altitude, evaluated where a sample is seen). Tolerance: the viewer's motion
// table is within 1 cm of the formula the bake evaluates (test above); measured 1.6e-5.
TEST(ViewerMotion, BakedFrameEqualsTheViewersDisplacedDensity) {
  for (const char* kind : {"blob", "noise", "noise+curl"}) {
    const bool curl = std::string(kind) == "noise+curl";
    cloudgen::Volume stat = testutil::synthetic(curl ? "noise" : kind);
    MotionParams m;
    m.wind_speed = 4;
    if (curl) m.curl_amplitude = 150, m.curl_scale = 250, m.curl_rise = 3;
    const int64_t frame = 12;
    const double fps = 0.5, t = frame / fps;
    cloudgen::MotionFrame baked = cloudgen::bake_frame(stat, m, frame, fps, 2);
    PreparedVolume moving_vol = prepare_volume(stat, 8), frame_vol = prepare_volume(baked.volume, 8);
    RenderSettings s;
    s.motion = m;
    FrameSetup moving = frame_at(moving_vol, s, t);
    RenderSettings still = s;
    still.motion.wind_speed = 0;
    still.motion.flow_speed = 0;
    still.motion.curl_amplitude = 0;  // the frame holds the distorted detail
    FrameSetup shown = frame_at(frame_vol, still, 0.0);
    const cloudgen::Volume& v = baked.volume;
    double worst = 0, peak = 0;
    uint32_t state = 11;
    auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
    for (int i = 0; i < 6000; ++i) {
      uint32_t x = next() % v.dims[0], y = next() % v.dims[1], z = next() % v.dims[2];
      glm::dvec3 p = glm::dvec3(v.origin[0], v.origin[1], v.origin[2]) + (glm::dvec3(x, y, z) + 0.5) * v.voxel_size;
      double a = reference_density(moving_vol, moving, p - moving.camera.eye);
      double b = reference_density(frame_vol, shown, p - shown.camera.eye);
      worst = std::max(worst, std::abs(a - b));
      peak = std::max(peak, b);
    }
    std::cout << kind << ": baked frame vs viewer at t = " << t << " s: max |diff| " << worst << " (peak " << peak << ")\n";
    EXPECT_GT(peak, 0.1) << kind;
    EXPECT_LE(worst, 1e-3) << kind;
  }
}

// The curl distortion of the detail lookup (cloudgen/curl_distortion.glsl): GL and the CPU
// reference agree with it on (the same texels, filtered by hand on both); it changes the image only
// through the detail (with erosion 0 the image is the same bit for bit), most at the base; and
// with curl_rise it churns over time while a still setting (rise 0) keeps the light volume.
TEST(ViewerMotion, CurlDistortsTheDetailOnGlAndCpuAlike) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("noise"), 8);
  ASSERT_TRUE(vol.has_detail);
  RenderSettings s;
  s.erosion = 0.8;
  s.exact_filter = true;
  s.motion.wind_speed = 0;
  s.motion.flow_speed = 0;
  RenderSettings curl = s;
  curl.motion.curl_amplitude = 120;
  curl.motion.curl_scale = 200;
  curl.motion.curl_rise = 0;
  const FrameSetup f0 = frame_at(vol, s, 0.0, 96, 54), f1 = frame_at(vol, curl, 0.0, 96, 54);
  EXPECT_EQ(f1.params.curl_amplitude_m, 120.0);
  EXPECT_EQ(f1.params.motion_on, 0.0) << "a curl field that does not rise is a still setting";
  const FrameImages gl0 = render_gl(vol, f0), gl1 = render_gl(vol, f1), cpu1 = render_cpu(vol, f1);
  const double changed = max_abs_diff(gl0.display, gl1.display), gl_cpu = rmse(gl1.linear, cpu1.linear);
  std::cout << "curl distortion: max |diff| vs none " << changed << ", GL vs CPU RMSE " << gl_cpu << "\n";
  EXPECT_GT(changed, 0.03) << "the distortion must show";
  EXPECT_LT(gl_cpu, 2e-4);
  // Only the detail moves: with no erosion the picture is the undistorted one exactly.
  RenderSettings flat = s, flat_curl = curl;
  flat.erosion = flat_curl.erosion = 0;
  EXPECT_EQ(max_abs_diff(render_cpu(vol, frame_at(vol, flat, 0.0, 96, 54)).linear, render_cpu(vol, frame_at(vol, flat_curl, 0.0, 96, 54)).linear), 0.0);
  // Rising, it moves with time and makes the frame a moving one.
  RenderSettings rising = curl;
  rising.motion.curl_rise = 5;
  const FrameSetup r0 = frame_at(vol, rising, 0.0, 96, 54), r1 = frame_at(vol, rising, 20.0, 96, 54);
  EXPECT_EQ(r1.params.motion_on, 1.0);
  EXPECT_EQ(max_abs_diff(render_gl(vol, r0).linear, gl1.linear), 0.0) << "time 0 is the still distortion";
  EXPECT_GT(max_abs_diff(render_gl(vol, r1).display, gl1.display), 0.02);
}

// Occupancy skipping looks cells up at displaced positions; make_frame shortens the large step by
// the displacement's slope so the samples kept are still those of the plain march. Strong shear
// (tops 4x faster) at a late time makes the slope large.
TEST(ViewerMotion, OccupancySkippingStaysExactWhileMoving) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 1);
  RenderSettings on;
  on.steps = 128;
  on.motion.wind_shear = 3.0;
  on.motion.wind_speed = 6.0;
  RenderSettings off = on;
  off.occupancy = false;
  for (bool gl : {true, false}) {
    FrameSetup fon = frame_at(vol, on, 240.0), foff = frame_at(vol, off, 240.0);
    EXPECT_LT(fon.params.large_step_count, frame_at(vol, on, 0.0).params.large_step_count)
        << "the large step must shrink while the displacement is steep";
    FrameImages a = testutil::render_on(gl, vol, fon);
    FrameImages b = testutil::render_on(gl, vol, foff);
    EXPECT_LE(max_abs_diff(a.linear, b.linear), 1e-5) << (gl ? "GL" : "CPU");
  }
}

// While the clouds move (box mode), occupied() reads make_frame's grid over the march box instead of
// looking the motion up (frame.cpp build_moved_occupancy). What the march relies on: an unmarked
// cell holds no density, nor does any point one large step (k small steps) away from it. Checked at
// random points of the march box against the CPU reference's density, for a box cloud and a
// tileable one, at two times, without shear (a tight grid, where a missing margin shows) and with
// strong shear (cells that gather many static cells); the grid must also leave cells to skip.
//
// Static cells of 4 (and 2) voxels: the moved grid keeps 8-voxel cells and the same large step,
// proven over 2 (4) static cells of the distance field (frame.cpp moved_reach_cells).
TEST(ViewerMotion, MovedOccupancyLeavesOutOnlyEmptySpace) {
  int built = 0;
  for (int static_cell : {8, 4, 2})
  for (const char* kind : {"blob", "noise"}) {
    PreparedVolume vol = prepare_volume(testutil::synthetic(kind), static_cell, 1);
    const PreparedVolume vol8 = static_cell == 8 ? vol : prepare_volume(testutil::synthetic(kind), 8, 1);
    for (glm::dvec2 ts : {glm::dvec2(95, 0), glm::dvec2(95, 3), glm::dvec2(240, 0), glm::dvec2(240, 3)}) {
      const double t = ts.x, shear = ts.y;
      const std::string at = std::string(kind) + " cell " + std::to_string(static_cell) + " t " +
                             std::to_string(int(t)) + " shear " + std::to_string(int(shear));
      RenderSettings s;
      s.steps = 128;
      s.motion.wind_shear = shear;
      s.motion.wind_speed = 6.0;
      s.erosion = 0;
      s.skipping = Skipping::Thesis;  // the grid's reader (distance skipping leaves it unbuilt)
      FrameSetup f = frame_at(vol, s, t);
      ASSERT_EQ(f.params.motion_on, 1.0);
      if (f.params.occupancy_skip < 0.5) {  // shear this steep leaves the large step under one small step
        EXPECT_TRUE(f.moved_occupancy.empty()) << at << ": a grid nothing reads";
        continue;
      }
      ++built;
      const glm::ivec3 n(f.params.moved_occ_dims);
      ASSERT_EQ(f.moved_occupancy.size(), size_t(n.x) * n.y * n.z) << at;
      EXPECT_NEAR(f.params.moved_occ_cell_m, 8 * vol.voxel_size, 1e-3 * vol.voxel_size) << at;
      if (static_cell != 8) {  // the same large step as with 8-voxel static cells
        const FrameSetup f8 = frame_at(vol8, s, t);
        EXPECT_EQ(f.params.large_step_count, f8.params.large_step_count) << at;
      }
      size_t marked = 0;
      for (uint8_t c : f.moved_occupancy) marked += c;
      EXPECT_GT(marked, 0u) << at;
      EXPECT_LT(double(marked), 0.8 * double(f.moved_occupancy.size())) << at << ": nothing to skip";
      const glm::dvec3 lo = f.params.march_min_m, ext = f.params.march_size_m;
      const double cell = f.params.moved_occ_cell_m, large = f.params.large_step_count * f.params.step_m;
      auto marked_at = [&](glm::dvec3 p) {
        glm::ivec3 c(glm::floor((p - lo) / cell));
        c = glm::clamp(c, glm::ivec3(0), n - 1);
        return f.moved_occupancy[(size_t(c.z) * n.y + c.y) * n.x + c.x] != 0;
      };
      uint32_t state = 11;
      auto next = [&] { return ((state = state * 1664525u + 1013904223u) >> 8) / double(1u << 24); };
      int unmarked = 0, dense = 0;
      for (int i = 0; i < 20000; ++i) {
        glm::dvec3 p = lo + ext * glm::dvec3(next(), next(), next());
        if (reference_density(vol, f, p) > 0) {
          ++dense;
          // The same property seen from the cloud: every point of the box within a large step of
          // density lies in a marked cell (this probes the grid's edge, where a wrong margin shows).
          // The corners of the large step's reach cross the most cell borders.
          for (int k = 0; k < 8; ++k) {
            glm::dvec3 q = p + glm::dvec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1) * (0.999 * large);
            if (glm::any(glm::lessThan(q, lo)) || glm::any(glm::greaterThanEqual(q, lo + ext))) continue;
            ASSERT_TRUE(marked_at(q)) << at << ": (" << q.x << ", " << q.y << ", " << q.z
                                      << ") is a large step from density but unmarked";
          }
        }
        if (marked_at(p)) continue;
        ++unmarked;
        // A large step from p in any direction, at most its length in each axis (L-infinity).
        glm::dvec3 d = (glm::dvec3(next(), next(), next()) * 2.0 - 1.0) * large;
        ASSERT_EQ(reference_density(vol, f, p), 0.0) << at << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
        ASSERT_EQ(reference_density(vol, f, p + d), 0.0) << at << " one large step from (" << p.x << ", "
                                                           << p.y << ", " << p.z << ")";
      }
      EXPECT_GT(unmarked, 2000) << at;
      EXPECT_GT(dense, 50) << at << ": the samples must reach the cloud";
    }
  }
  std::cout << "moved grids built in " << built << " of 24 cases\n";
  EXPECT_GE(built, 12) << "of 24 cases: the thesis scheme must skip in half at least";
}

// The moved grid is built for its readers only: the thesis scheme's march, and the light march
// skipping empty cells (render.occupancy_light; while the clouds move it reads the grid under either
// scheme, apply_motion). Distance skipping alone, the defaults, no skipping and layer mode leave it
// empty, and their images stay those of no skipping (Skipping.DistanceSkippingStaysExactWhileMoving).
TEST(ViewerMotion, MovedGridIsBuiltForItsReadersOnly) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("noise"), 4, 2);  // tiles: layer mode too
  struct Case { const char* name; Skipping skipping; bool light; bool layer; bool built; };
  const Case cases[] = {{"distance", Skipping::Distance, false, false, false},
                        {"distance + occupancy_light", Skipping::Distance, true, false, true},
                        {"none", Skipping::None, false, false, false},
                        {"thesis", Skipping::Thesis, false, false, true},
                        {"thesis + occupancy_light", Skipping::Thesis, true, false, true},
                        {"thesis, layer mode", Skipping::Thesis, false, true, false}};
  for (const Case& c : cases) {
    RenderSettings s;
    s.steps = 128;
    s.skipping = c.skipping;
    s.occupancy_light = c.light;
    if (c.layer) s.mode = PlaceMode::Layer;
    FrameSetup f = frame_at(vol, s, 60.0);
    ASSERT_EQ(f.params.motion_on, 1.0) << c.name;
    EXPECT_EQ(!f.moved_occupancy.empty(), c.built) << c.name;
    if (c.built) {
      const glm::ivec3 n(f.params.moved_occ_dims);
      EXPECT_EQ(f.moved_occupancy.size(), size_t(n.x) * n.y * n.z) << c.name;
    }
  }
}

// The grid's margin, where random points rarely look: a volume whose only density is three voxels,
// each in the corner of its coarse cell, so density reaches the cell's faces. Around each voxel's
// moved image, every point a large step from density must lie in a marked cell, at many times (the
// moved grid's offset against the static cells changes with time) and without shear (the tightest
// grid). A grid that marked only the cells holding density fails here. (Its half-voxel margin is
// not what this catches: removed, the test still passes, also at 77 steps, where the large step is
// 0.01 voxel under the clearance. Measured 2026-12-06; the margin stays, as the proof needs it.)
// Wind alone (no flow map): a steep flow over this small volume would turn the thesis scheme off
// (its step under one small step), and make_frame builds no grid that nothing reads.
TEST(ViewerMotion, MovedOccupancyKeepsItsMarginAtCellFaces) {
  cloudgen::Volume v = testutil::synthetic("blob");
  std::fill(v.density.begin(), v.density.end(), 0.f);
  const std::array<std::array<uint32_t, 3>, 3> dots = {{{47, 23, 47}, {56, 16, 39}, {31, 31, 64}}};
  for (const auto& d : dots) v.density[v.index(d[0], d[1], d[2])] = 1.f;
  for (int static_cell : {8, 4}) {
  PreparedVolume vol = prepare_volume(v, static_cell, 1);
  int dense = 0;
  for (int ti = 0; ti < 24; ++ti) {
    RenderSettings s;
    s.steps = 96;
    s.motion.wind_shear = 0.0;
    s.motion.wind_speed = 5.0;
    s.motion.flow_up = s.motion.flow_forward = 0.0;  // no stretch: the thesis scheme stays on and reads the grid
    s.erosion = 0;
    s.skipping = Skipping::Thesis;
    const double t = 20.0 + 7.3 * ti;
    FrameSetup f = frame_at(vol, s, t);
    ASSERT_EQ(f.params.motion_on, 1.0);
    ASSERT_EQ(f.params.occupancy_skip, 1.0) << "t " << t << ": the thesis scheme reads this grid";
    const glm::ivec3 n(f.params.moved_occ_dims);
    ASSERT_EQ(f.moved_occupancy.size(), size_t(n.x) * n.y * n.z);
    const glm::dvec3 lo = f.params.march_min_m, hi = lo + f.params.march_size_m;
    const double cell = f.params.moved_occ_cell_m, large = f.params.large_step_count * f.params.step_m;
    auto marked_at = [&](glm::dvec3 p) {
      glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((p - lo) / cell)), glm::ivec3(0), n - 1);
      return f.moved_occupancy[(size_t(c.z) * n.y + c.y) * n.x + c.x] != 0;
    };
    uint32_t state = 5 + ti;
    auto next = [&] { return ((state = state * 1664525u + 1013904223u) >> 8) / double(1u << 24); };
    for (const auto& d : dots) {
      glm::dvec3 c = f.params.volume_min_m + (glm::dvec3(d[0], d[1], d[2]) + 0.5) * vol.voxel_size;
      double h = (c.y - f.params.volume_min_m.y) / f.params.volume_size_m.y;
      c += table_displacement(f, h);  // where the voxel is seen at this time
      for (int i = 0; i < 200; ++i) {
        glm::dvec3 p = c + (glm::dvec3(next(), next(), next()) * 2.0 - 1.0) * vol.voxel_size;
        if (reference_density(vol, f, p) <= 0) continue;
        ++dense;
        for (int k = 0; k < 8; ++k) {
          glm::dvec3 q = p + glm::dvec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1) * (0.999 * large);
          if (glm::any(glm::lessThan(q, lo)) || glm::any(glm::greaterThanEqual(q, hi))) continue;
          ASSERT_TRUE(marked_at(q)) << "cell " << static_cell << " t " << t << ": (" << q.x << ", " << q.y << ", "
                                    << q.z << ") is a large step from density but unmarked";
        }
      }
    }
  }
  EXPECT_GT(dense, 2000) << "the samples must find the voxels' density";
  }
}

// Time 0 with the default (moving) parameters, and any time with the motion switched off, are the
// static image bit for bit; the defaults move the clouds by time 60.
TEST(ViewerMotion, TimeZeroIsStaticAndTheDefaultsMove) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  RenderSettings s;
  RenderSettings still = s;
  still.motion.wind_speed = 0;
  still.motion.flow_speed = 0;
  FrameImages zero = render_gl(vol, frame_at(vol, s, 0.0));
  FrameImages off = render_gl(vol, frame_at(vol, still, 100.0));
  EXPECT_EQ(max_abs_diff(zero.linear, off.linear), 0.0);
  FrameImages later = render_gl(vol, frame_at(vol, s, 60.0));
  int changed = 0;
  for (int y = 0; y < 90; ++y)
    for (int x = 0; x < 160; ++x)
      if (std::abs(later.display.at(x, y)[0] - zero.display.at(x, y)[0]) > 0.02) ++changed;
  EXPECT_GT(changed, 160 * 90 / 50) << "the default wind and flow must visibly move the cloud in 60 s";
}

TEST(ViewerMotionCli, FramesWriteAPatternOrOnlyTheLastFrame) {
  testutil::TempDir dir;
  std::string err;
  std::vector<std::string> common = {"synthetic:blob", "--headless", "--size", "48x27", "--time", "10",
                                     "--frames", "3", "--fps", "0.05"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = common;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  ASSERT_EQ(run(with({"--out", (dir.path / "f_%03d.png").string()}), &err), 0) << err;
  for (const char* f : {"f_000.png", "f_001.png", "f_002.png"}) EXPECT_TRUE(fs::exists(dir.path / f)) << f;
  EXPECT_FALSE(fs::exists(dir.path / "f_003.png"));
  EXPECT_NE(read_text(dir.path / "f_000.png"), read_text(dir.path / "f_002.png")) << "time must advance";
  ASSERT_EQ(run(with({"--out", (dir.path / "last.png").string()}), &err), 0) << err;
  EXPECT_EQ(read_text(dir.path / "last.png"), read_text(dir.path / "f_002.png")) << "a plain --out is the last frame";
  for (const char* bad : {"x_%s.png", "x_%d_%d.png", "x_%10d.png", "x_%"}) {
    EXPECT_EQ(run(with({"--out", (dir.path / bad).string()}), &err), 1) << bad;
    EXPECT_NE(err.find("frame pattern"), std::string::npos) << err;
  }
  EXPECT_EQ(run({"synthetic:blob", "--headless", "--time", "fast", "--out", (dir.path / "y.png").string()}, &err), 1);
  EXPECT_NE(err.find("--time"), std::string::npos) << err;
  EXPECT_EQ(run({"synthetic:blob", "--headless", "--set", "motion.wind_speed=-3", "--out",
                 (dir.path / "y.png").string()}, &err), 1);
  EXPECT_NE(err.find("motion.wind_speed"), std::string::npos) << err;
}

// A flow map image on the viewer's command line: the procedural map's own image gives the
// procedural picture within a display level or two, a coarse map moves the cloud elsewhere, and a
// bad file exits 1 naming it.
TEST(ViewerMotionCli, FlowMapImageMovesTheClouds) {
  testutil::TempDir dir;
  cloudgen::write_flow_map_png((dir.path / "fine.png").string(), 256, 64);
  cloudgen::write_flow_map_png((dir.path / "coarse.png").string(), 4, 2);
  std::string err;
  auto frame = [&](const std::string& map, const std::string& out) {
    std::vector<std::string> a = {"synthetic:blob", "--headless", "--size", "96x54", "--time", "40",
                                  "--set", "motion.wind_speed=0", "--set", "motion.flow_speed=0.02",
                                  "--set", "motion.flow_forward=600", "--out", (dir.path / out).string()};
    if (!map.empty()) a.insert(a.end(), {"--set", "motion.flow_map=" + map});
    EXPECT_EQ(run(a, &err), 0) << err;
    return read_png((dir.path / out).string());
  };
  const Image proc = frame("", "proc.png"), fine = frame((dir.path / "fine.png").string(), "fine_frame.png"),
              coarse = frame((dir.path / "coarse.png").string(), "coarse_frame.png");
  const double fine_diff = max_abs_diff(proc, fine), coarse_diff = max_abs_diff(proc, coarse);
  std::cout << "flow map image vs procedural: max |diff| fine " << fine_diff << ", coarse " << coarse_diff << "\n";
  EXPECT_LT(fine_diff, 3.0 / 255);
  EXPECT_GT(coarse_diff, 0.05);
  EXPECT_EQ(run({"synthetic:blob", "--headless", "--set", "motion.flow_map=" + (dir.path / "none.png").string(), "--out",
                 (dir.path / "y.png").string()},
                &err),
            1);
  EXPECT_NE(err.find("motion.flow_map " + (dir.path / "none.png").string() + ": no such file"), std::string::npos) << err;
}

// ------------------------------------------------------------------------------ temporal upsampling

namespace {

// Pixels whose display value differs from the full render's by more than `bound` in any channel.
int ghost_pixels(const Image& a, const Image& b, double bound) {
  int n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      double d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, double(std::abs(a.at(x, y)[c] - b.at(x, y)[c])));
      if (d > bound) ++n;
    }
  return n;
}

// A camera orbiting the volume's centre: `yaw` degrees around y from the default view.
Camera orbit(const PreparedVolume& vol, double yaw, double aspect) {
  Camera c = default_camera(vol, 60, aspect);
  glm::dvec3 d = c.eye - c.target;
  double a = glm::radians(yaw);
  c.eye = c.target + glm::dvec3(d.x * std::cos(a) - d.z * std::sin(a), d.y, d.x * std::sin(a) + d.z * std::cos(a));
  return c;
}

}  // namespace

TEST(TemporalUpsampling, CrossMatrixIsTheSeedsAndVisitsEveryPixelOnceIn16Frames) {
  const int m[4][4] = {{0, 8, 2, 10}, {12, 4, 14, 6}, {3, 11, 1, 9}, {15, 7, 13, 5}};
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(reference_cross_matrix(x, y), m[y][x]) << x << "," << y;
  for (int start : {0, 5, 1000}) {
    int visits[4][4] = {};
    for (int f = start; f < start + 16; ++f) {
      glm::ivec2 o = reference_cross_matrix_offset(f);
      ASSERT_TRUE(o.x >= 0 && o.x < 4 && o.y >= 0 && o.y < 4);
      EXPECT_EQ(m[o.y][o.x], f % 16);
      ++visits[o.y][o.x];
    }
    for (auto& row : visits)
      for (int v : row) EXPECT_EQ(v, 1) << "16 frames from " << start;
  }
}

// The air the sparse pixels pass on (temporal.glsl): carried to its own distance it is what it
// was; along a uniform medium it is exact at any distance (analytic: T = exp(-sigma t),
// I = L (1 - T)); through clear air the light grows in proportion to the distance.
TEST(TemporalUpsampling, AirCarriedToAnotherDistanceIsExactInAUniformMedium) {
  const glm::dvec3 sigma(2.0e-5, 1.2e-5, 0.6e-5), radiance(0.3, 0.5, 0.9);  // per metre; the air's own light
  auto uniform = [&](double t, glm::dvec3& i, glm::dvec3& tr) {
    tr = glm::exp(-sigma * t);
    i = radiance * (glm::dvec3(1.0) - tr);
  };
  for (double t_k : {50.0, 3000.0, 40000.0}) {
    glm::dvec3 i_k, tr_k;
    uniform(t_k, i_k, tr_k);
    for (double t : {t_k, 10.0, 0.5 * t_k, 2.0 * t_k, 90000.0}) {
      glm::dvec3 i, tr, i_want, tr_want;
      reference_air_carried(i_k, tr_k, t_k, t, i, tr);
      uniform(t, i_want, tr_want);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(tr[c], tr_want[c], 1e-9 * tr_want[c]) << "t_k " << t_k << " t " << t << " channel " << c;
        EXPECT_NEAR(i[c], i_want[c], 1e-6 * i_want[c]) << "t_k " << t_k << " t " << t << " channel " << c;
      }
    }
  }
  glm::dvec3 i, tr;  // clear air (T = 1): the light of the air in proportion to the distance
  reference_air_carried(glm::dvec3(0.01, 0.02, 0.04), glm::dvec3(1.0), 1000.0, 2500.0, i, tr);
  EXPECT_NEAR(i.x, 0.025, 1e-12);
  EXPECT_NEAR(i.z, 0.1, 1e-12);
  EXPECT_EQ(tr, glm::dvec3(1.0));
}

namespace {
// Whether `pass` drew in the frame `g` timed (GpuTimings::passes lists only the passes that drew).
bool pass_ran(const GpuTimings& g, const char* pass) {
  for (const auto& p : g.passes)
    if (p.first == pass) return true;
  return false;
}
}  // namespace

// A still camera over still clouds: after 16 frames every pixel has been marched once and the
// history maps pixel to pixel, so the image is the full-resolution render's (the jitter of the
// frame each pixel was marched in is the only difference). Held frames compose only the pixels
// they march, over last frame's image, so each pixel's air in front of the background is its own
// sample's too (with the air bilinear from the sparse pixels at every frame it was 64.6 dB). Also
// after a resize-free settings change the history is dropped (the first frame is the spatial
// upsample, visibly worse).
TEST(TemporalUpsampling, StillViewConvergesToTheFullRenderIn16Frames) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 160, h = 96;
  Camera cam = default_camera(vol, 60, double(w) / h);
  Sun sun = default_sun(cam);
  RenderSettings s;
  RenderSettings t = s;
  t.temporal = true;
  GlRenderer full{ShaderSource()}, temporal{ShaderSource()};
  full.set_volume(vol);
  temporal.set_volume(vol);
  double first = 0;
  for (int f = 0; f < 16; ++f) {
    t.frame = f;
    GpuTimings g;
    temporal.render(make_frame(vol, t, cam, sun, w, h), &g);
    // The first frame has no history (the spatial upsample: the resolve and the full compose);
    // every later one holds it (nothing moved: the held sparse pass alone, which stores this
    // frame's pixels into the layer and the image; the image below checks it too).
    EXPECT_EQ(pass_ran(g, "temporal_resolve"), f == 0) << "frame " << f;
    EXPECT_EQ(pass_ran(g, "temporal_compose"), f == 0) << "frame " << f;
    EXPECT_EQ(pass_ran(g, "clouds_sparse"), f == 0) << "frame " << f;
    EXPECT_EQ(pass_ran(g, "clouds_sparse_held"), f > 0) << "frame " << f;
    if (f == 0) {
      s.frame = 0;
      full.render(make_frame(vol, s, cam, sun, w, h));
      first = psnr(temporal.read_back().display, full.read_back().display);
    }
  }
  s.frame = 15;
  full.render(make_frame(vol, s, cam, sun, w, h));
  FrameImages a = temporal.read_back(), b = full.read_back();
  double converged = psnr(a.display, b.display);
  std::cout << "temporal vs full PSNR: frame 0 " << first << " dB, frame 15 " << converged << " dB\n";
  EXPECT_GE(converged, 70.0) << "every pixel's cloud and air must be its own after 16 held frames (issue: 40 dB)";
  EXPECT_GT(converged, first + 3.0) << "the history must add detail the spatial upsample lacks";
}

// render.compute runs the full cloud pass, the temporal passes (moving and held), the bloom and the
// tone map as compute shaders: the same pixels, so the same bits as the full-screen triangles, at a size that is a multiple of neither
// the 8x8 work group nor the 4x4 block, through held frames, a camera move (the fragment passes of
// a moving frame over the compute frames' history) and held frames again.
TEST(TemporalUpsampling, ComputePassesStoreTheFragmentPassesBits) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 101, h = 57;
  Camera cam = default_camera(vol, 60, double(w) / h);
  const Sun sun = default_sun(cam);
  for (bool temporal : {false, true}) {
    SCOPED_TRACE(temporal ? "temporal" : "full");
    GlRenderer frag{ShaderSource()}, comp{ShaderSource()};
    frag.set_volume(vol);
    comp.set_volume(vol);
    RenderSettings s;
    s.temporal = temporal;
    RenderSettings c = s;
    c.compute = true;
    Camera at = cam;
    int computed = 0;
    for (int f = 0; f < (temporal ? 14 : 2); ++f) {
      if (f == 7) at.eye += glm::dvec3(40, 10, 0);  // a move: one frame of the fragment passes
      s.frame = c.frame = f;
      GpuTimings gf, gc;
      frag.render(make_frame(vol, s, at, sun, w, h), &gf);
      comp.render(make_frame(vol, c, at, sun, w, h), &gc);
      const FrameImages a = frag.read_back(), b = comp.read_back();
      EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << "frame " << f;
      EXPECT_GT(image_stats(b.display).stddev, 0.02) << "frame " << f;
      const char* pass = temporal ? "clouds_sparse_held" : "clouds";
      EXPECT_FALSE(pass_ran(gf, (std::string(pass) + " (compute)").c_str())) << "frame " << f;
      computed += pass_ran(gc, (std::string(pass) + " (compute)").c_str()) ? 1 : 0;
      EXPECT_EQ(pass_ran(gf, pass), pass_ran(gc, (std::string(pass) + " (compute)").c_str())) << "frame " << f;
      for (const char* moved : {"clouds_sparse", "temporal_resolve", "temporal_compose"})  // frames 0 and 7
        EXPECT_EQ(pass_ran(gf, moved), pass_ran(gc, (std::string(moved) + " (compute)").c_str())) << moved << ", frame " << f;
      if (temporal) {
        EXPECT_EQ(pass_ran(gc, "temporal_resolve (compute)"), f == 0 || f == 7) << "frame " << f;
      }
      for (const char* post : {"bloom_bright", "bloom_blur_x", "bloom_blur_y", "tonemap"}) {
        EXPECT_TRUE(pass_ran(gf, post)) << post << ", frame " << f;
        EXPECT_TRUE(pass_ran(gc, (std::string(post) + " (compute)").c_str())) << post << ", frame " << f;
      }
    }
    EXPECT_EQ(computed, temporal ? 12 : 2) << "every held frame (all but the first and the move's) and every full frame";
  }
}

// A held frame (nothing moved) draws only the pixels it marches, into last frame's resolved layer
// and composed image kept in place: every other pixel of both must stay exactly as it was, and
// the marched ones must take their fresh value. (A held frame that drew into the other copy of
// the history would bring back the layer of two frames ago: the images pass, the history not.)
TEST(TemporalUpsampling, HeldFramesChangeOnlyThePixelsTheyMarch) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 90, h = 54;  // partial 4x4 blocks at the right and top edges
  Camera cam = default_camera(vol, 60, double(w) / h);
  Sun sun = default_sun(cam);
  RenderSettings t;
  t.temporal = true;
  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  Image layer, image;
  int changed_total = 0;
  for (int f = 0; f < 20; ++f) {
    t.frame = f;
    r.render(make_frame(vol, t, cam, sun, w, h));
    Image now = r.read_target("cloud_layer"), composed = r.read_target("hdr"), fresh = r.read_target("cloud_quarter");
    if (f > 0) {
      const glm::ivec2 off = reference_cross_matrix_offset(f);
      int marched = 0, differ = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const bool mine = (x & 3) == off.x && (y & 3) == off.y;
          for (int c = 0; c < 4; ++c) {
            if (mine) {
              ASSERT_EQ(now.at(x, y)[c], fresh.at(x >> 2, y >> 2)[c]) << "frame " << f << " pixel " << x << "," << y;
            } else {
              ASSERT_EQ(now.at(x, y)[c], layer.at(x, y)[c]) << "frame " << f << ": held pixel " << x << "," << y;
              ASSERT_EQ(composed.at(x, y)[c], image.at(x, y)[c]) << "frame " << f << ": composed pixel " << x << "," << y;
            }
          }
          marched += mine;
          if (mine && composed.at(x, y)[0] != image.at(x, y)[0]) ++differ;
        }
      EXPECT_EQ(marched, ((w - off.x + 3) / 4) * ((h - off.y + 3) / 4)) << "frame " << f;
      changed_total += differ;
    }
    layer = now, image = composed;
  }
  // Frame 0's spatial upsample gave the unmarched pixels an interpolated value, which the held
  // frames replace by their own: the composed image must change somewhere.
  EXPECT_GT(changed_total, w * h / 4);
}

// A held frame also keeps last frame's ground ("scene", which only the ground pass writes): the
// same settings, sun, camera, time and volume draw the same ground. Every frame must give the bits
// of a renderer that draws the ground every frame, through held frames, a camera move, a sun change,
// moving clouds (each time step redraws: the shadow moves) and a new volume; and the ground must be
// drawn exactly in the frames that are not held.
TEST(TemporalUpsampling, HeldFramesKeepTheGroundTheyWouldDraw) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 96, h = 54;
  Camera cam = default_camera(vol, 60, double(w) / h);
  Sun sun = default_sun(cam);
  RenderSettings t;
  t.temporal = true;
  GlRenderer kept{ShaderSource()}, drawn{ShaderSource()};
  kept.set_volume(vol);
  drawn.set_volume(vol);
  drawn.set_ground_reuse(false);
  std::set<int> redraw;  // the frames that change something the ground shows (and frame 0)
  for (int f = 0; f < 22; ++f) {
    if (f == 0) redraw.insert(f);
    if (f == 5) cam.eye += glm::dvec3(30, 0, -20), redraw.insert(f);  // level: the air LUT stays
    if (f == 9) sun.elevation_deg += 7, redraw.insert(f);
    if (f == 13 || f == 14) t.time += 20, redraw.insert(f);  // the defaults move the clouds and their shadow
    if (f == 18) {
      kept.set_volume(vol);
      drawn.set_volume(vol);
      redraw.insert(f);
    }
    t.frame = f;
    const int before = kept.stats().ground_draws;
    GpuTimings gk, gd;
    kept.render(make_frame(vol, t, cam, sun, w, h), &gk);
    drawn.render(make_frame(vol, t, cam, sun, w, h), &gd);
    const bool held = pass_ran(gk, "clouds_sparse_held");
    EXPECT_EQ(held, redraw.count(f) == 0) << "frame " << f;
    EXPECT_EQ(kept.stats().ground_draws - before, held ? 0 : 1) << "frame " << f;
    EXPECT_EQ(pass_ran(gk, "ground"), !held) << "frame " << f;
    EXPECT_TRUE(pass_ran(gd, "ground")) << "frame " << f;
    EXPECT_EQ(max_abs_diff(kept.read_back().linear, drawn.read_back().linear), 0.0) << "frame " << f;
  }
  EXPECT_EQ(kept.stats().ground_draws, int(redraw.size()));
  EXPECT_EQ(drawn.stats().ground_draws, 22);
  // The ground is in the picture (not the sky everywhere), so keeping it is not keeping nothing.
  const Image distance = kept.read_target("scene", 1);
  int ground = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ground += distance.at(x, y)[0] < 0.5f * float(CV_NO_HIT) ? 1 : 0;
  EXPECT_GT(ground, w * h / 10);
}

// A shader hot reload (the window's R key) must not keep what the old programs computed: the
// light volume and shadow map are rebuilt and the temporal history, held a frame before, dropped.
TEST(TemporalUpsampling, ReloadedShadersRecomputeTheCachesAndTheHistory) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 64, h = 36;
  Camera cam = default_camera(vol, 60, double(w) / h);
  Sun sun = default_sun(cam);
  RenderSettings t;
  t.temporal = true;
  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  GpuTimings g;
  for (int f = 0; f < 2; ++f) {
    t.frame = f;
    r.render(make_frame(vol, t, cam, sun, w, h), &g);
  }
  ASSERT_TRUE(pass_ran(g, "clouds_sparse_held")) << "the second frame holds the history";
  const int light = r.stats().light_volume_builds, shadow = r.stats().shadow_map_builds;
  ASSERT_GT(light, 0);
  ASSERT_GT(shadow, 0);
  r.reload_shaders();
  t.frame = 2;
  r.render(make_frame(vol, t, cam, sun, w, h), &g);
  EXPECT_TRUE(pass_ran(g, "clouds_sparse")) << "after a reload the history is not held";
  EXPECT_FALSE(pass_ran(g, "clouds_sparse_held"));
  EXPECT_EQ(r.stats().light_volume_builds, light + 1);
  EXPECT_EQ(r.stats().shadow_map_builds, shadow + 1);
}

// A camera pan and moving clouds: the reprojected, neighbourhood-clamped history must not leave
// ghosts. Each frame is compared with the full render of the same camera, time and frame index;
// a pixel off by more than 0.1 (display units, any channel) counts as a ghost.
TEST(TemporalUpsampling, PanAndMovingCloudsLeaveNoGhosts) {
  gl_context();
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8);
  const int w = 160, h = 96;
  GlRenderer full{ShaderSource()}, temporal{ShaderSource()};
  full.set_volume(vol);
  temporal.set_volume(vol);
  struct Case { const char* name; double yaw_per_frame, seconds_per_frame; };
  for (Case c : {Case{"pan", 0.75, 0.0}, Case{"wind", 0.0, 4.0}, Case{"both", 0.75, 4.0}}) {
    RenderSettings s;
    s.motion.wind_speed = 15;
    int worst = 0;
    double worst_rmse = 0;
    for (int f = 0; f < 30; ++f) {
      int moving = std::max(0, f - 16);  // 16 still frames to converge, then move for 14
      Camera cam = orbit(vol, moving * c.yaw_per_frame, double(w) / h);
      s.frame = f;
      s.time = moving * c.seconds_per_frame;
      RenderSettings t = s;
      t.temporal = true;
      Sun sun = default_sun(default_camera(vol, 60, double(w) / h));
      temporal.render(make_frame(vol, t, cam, sun, w, h));
      if (f < 16) continue;
      full.render(make_frame(vol, s, cam, sun, w, h));
      FrameImages a = temporal.read_back(), b = full.read_back();
      int ghosts = ghost_pixels(a.display, b.display, 0.1);
      if (ghosts > worst && getenv("CV_DUMP")) {
        write_png(std::string("/tmp/mv/g_") + c.name + "_t.png", a.display);
        write_png(std::string("/tmp/mv/g_") + c.name + "_f.png", b.display);
        std::cout << c.name << " frame " << f << " ghosts " << ghosts << "\n";
      }
      worst = std::max(worst, ghosts);
      worst_rmse = std::max(worst_rmse, rmse(a.display, b.display));
    }
    std::cout << c.name << ": worst frame " << worst << " ghost pixels of " << w * h << ", worst RMSE "
              << worst_rmse << "\n";
    EXPECT_LE(worst, w * h / 100) << c.name << ": more than 1% of the pixels ghost";
  }
}
