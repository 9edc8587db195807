// Render-time detail (render.detail, issue 44 item 1; detail_texture.h, shaders/medium.glsl
// fine_detail_threshold): the texture is libnoise3d's Worley fBm over exactly one tile, so it wraps
// seamlessly, and the same every time; GL and the CPU reference render the detailed cloud alike;
// skipping stays exact with it (it only erodes); it changes the cloud, and strength 0 is off.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <noise3d/noise3d.h>

#include "cloudviewer/detail_texture.h"
#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util_viewer.h"

using namespace cloudviewer;
using testutil::with;

namespace {

// Smaller than the other render tests' frame: the CPU reference marches every pixel of it.
const int kW = testutil::sized(96, 48), kH = testutil::sized(54, 27);
auto& render = testutil::render_on;  // render(on_gl, vol, frame)

const PreparedVolume& blob() {
  static const PreparedVolume v = prepare_volume(testutil::synthetic("blob"), 8);
  return v;
}

// The blob (1152 x 576 x 1152 m) from a camera off its side, the detail tiled every 100 m (finest
// Worley cells ~6 m) so that it shows at 96 x 54.
FrameSetup close_frame(const PreparedVolume& vol, RenderSettings s) {
  Camera cam;
  cam.eye = vol.center() + glm::dvec3(-150, 100, -750);
  cam.target = vol.center() + glm::dvec3(0, 60, 0);
  cam.fov_y_deg = 50;
  return make_frame(vol, s, cam, default_sun(cam), kW, kH);
}

// Mean |a - b| of the display images over pixels where `cloud` differs from `sky` (the cloud's pixels).
double mean_diff_over_cloud(const Image& a, const Image& b, const Image& cloud, const Image& sky, int* count) {
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i + 3 < a.rgba.size(); i += 4) {
    bool is_cloud = false;
    for (int c = 0; c < 3; ++c) is_cloud = is_cloud || std::abs(cloud.rgba[i + c] - sky.rgba[i + c]) > 0.01f;
    if (!is_cloud) continue;
    ++n;
    for (int c = 0; c < 3; ++c) sum += std::abs(a.rgba[i + c] - b.rgba[i + c]) / 3.0;
  }
  *count = n;
  return n ? sum / n : 0.0;
}

}  // namespace

// The texture is the stated libnoise3d fBm, stretched to [0, 1], over exactly one tile: each texel
// equals the point function at its lattice position; the value one tile on along any axis is the
// same (so the texture wraps seamlessly), and the step across the wrap (last texel to first) is no
// larger than between neighbours inside, while a step across a cut made mid-tile is (the check can
// fail). Asked again, the same values.
TEST(RenderDetail, TextureTilesSeamlesslyAndIsDeterministic) {
  const int n = 32;
  const std::vector<float>& t = *detail_texture(n);
  ASSERT_EQ(t.size(), size_t(n) * n * n);
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
  EXPECT_EQ(*lo, 0.f);
  EXPECT_EQ(*hi, 1.f);
  auto at = [&](int x, int y, int z) { return double(t[(size_t(z) * n + y) * n + x]); };

  noise3d::FractalParams fp;
  fp.kind = noise3d::Kind::Worley;
  fp.period = noise3d::Period::cube(kDetailBaseCells);
  fp.seed = kDetailSeed;
  fp.octaves = kDetailOctaves;
  double vmin = 1e9, vmax = -1e9;  // the stretch's ends, from the raw grid
  {
    std::vector<float> raw(t.size());
    const noise3d::MinMax mm = noise3d::evaluate_grid(fp, noise3d::GridRegion::whole(n), raw.data());
    vmin = mm.min, vmax = mm.max;
  }
  const double s = double(kDetailBaseCells) / n;  // lattice units per texel
  uint32_t h = 7;
  for (int k = 0; k < 64; ++k) {
    const int x = int(testutil::lcg(h) % n), y = int(testutil::lcg(h) % n), z = int(testutil::lcg(h) % n);
    const double v = noise3d::evaluate(fp, x * s, y * s, z * s);
    EXPECT_NEAR(at(x, y, z), (v - vmin) / (vmax - vmin), 1e-5) << x << "," << y << "," << z;
    const double p = kDetailBaseCells;  // one tile on, along each axis
    EXPECT_EQ(noise3d::evaluate(fp, x * s + p, y * s, z * s), v);
    EXPECT_EQ(noise3d::evaluate(fp, x * s, y * s + p, z * s), v);
    EXPECT_EQ(noise3d::evaluate(fp, x * s, y * s, z * s + p), v);
  }
  for (int axis = 0; axis < 3; ++axis) {
    auto along = [&](int i, int a, int b) {
      return axis == 0 ? at(i, a, b) : axis == 1 ? at(a, i, b) : at(a, b, i);
    };
    double seam = 0, inside = 0, cut = 0;
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        seam += std::abs(along(n - 1, a, b) - along(0, a, b));
        cut += std::abs(along(n / 2 - 1, a, b) - along(3 * n / 4, a, b));
        for (int i = 0; i + 1 < n; ++i) inside += std::abs(along(i, a, b) - along(i + 1, a, b)) / (n - 1);
      }
    std::cout << "axis " << axis << ": mean step across the wrap " << seam / (n * n) << ", inside "
              << inside / (n * n) << ", across a mid-tile cut " << cut / (n * n) << "\n";
    EXPECT_LT(seam, 1.25 * inside) << "axis " << axis;
    EXPECT_GT(cut, 2.0 * inside) << "axis " << axis << ": the check can fail";
  }
  const std::vector<float> again = *detail_texture(n);
  EXPECT_EQ(again, t);
}

// GL and the CPU reference with the detail on, close enough to see it: the thresholds of
// ViewerRender.GlMatchesCpuReference* (50 dB with exact filtering, 40 dB with the texture unit).
TEST(RenderDetail, GlMatchesCpuReference) {
  const PreparedVolume& vol = blob();
  for (bool exact : {true, false}) {
    RenderSettings s = with({"render.steps=64", "render.detail=true", "render.detail_period=100"});
    s.exact_filter = exact;
    const FrameSetup f = close_frame(vol, s);
    ASSERT_GT(f.params.fine_detail_strength, 0.0);
    const FrameImages gl = render(true, vol, f), cpu = render(false, vol, f);
    EXPECT_EQ(image_stats(gl.linear).nonfinite, 0);
    const double p = psnr(gl.display, cpu.display);
    std::cout << "detail on: PSNR GL vs CPU (" << (exact ? "exact" : "hardware") << " filter) " << p << " dB\n";
    EXPECT_GT(p, exact ? 50.0 : 40.0);
  }
}

// The detail only erodes, so the occupancy grid and the distance field (built without it) still
// prove empty space: render.skipping=none, thesis and distance (the default) give the same image,
// bit for bit, on GL and (none and distance) on the CPU reference.
TEST(RenderDetail, SkippingStaysExact) {
  const PreparedVolume& vol = blob();
  for (bool on_gl : {true, false}) {
    const char* what = on_gl ? "GL" : "CPU";
    RenderSettings s = with({"render.steps=64", "render.detail=true", "render.detail_period=100"});
    s.skipping = Skipping::None;
    const FrameImages none = render(on_gl, vol, close_frame(vol, s));
    s.skipping = Skipping::Distance;
    const FrameImages dist = render(on_gl, vol, close_frame(vol, s));
    EXPECT_GT(image_stats(none.display).stddev, 0.01) << what << ": a picture to compare";
    EXPECT_EQ(max_abs_diff(none.linear, dist.linear), 0.0) << what << " distance";
    EXPECT_EQ(max_abs_diff(none.display, dist.display), 0.0) << what << " distance";
    if (on_gl) {  // the thesis scheme too (on GL alone: the CPU runs the same lines)
      s.skipping = Skipping::Thesis;
      EXPECT_EQ(max_abs_diff(none.linear, render(true, vol, close_frame(vol, s)).linear), 0.0) << what << " thesis";
    }
  }
}

// On against off: the cloud's pixels change, by 0.025 on average (display, 0..1; llvmpipe and the
// CPU reference alike, 0.01 asserted); strength 0 is the image without detail, bit for bit; and
// the texture is laid a whole number of times over each axis of the box, as near
// render.detail_period as that allows.
TEST(RenderDetail, ChangesTheCloudAndStrengthZeroIsOff) {
  const PreparedVolume& vol = blob();
  const RenderSettings base = with({"render.steps=64", "render.detail_period=100"});
  RenderSettings off = base, on = base, zero = base, sky = base;
  off.detail = false;
  on.detail = true;
  zero.detail = true;
  zero.detail_strength = 0;
  sky.density = 0;
  const FrameSetup f_on = close_frame(vol, on);
  EXPECT_EQ(f_on.params.fine_detail_repeats.x, std::round(vol.dims[0] * vol.voxel_size / 100.0));
  EXPECT_EQ(f_on.params.fine_detail_repeats.y, std::round(vol.dims[1] * vol.voxel_size / 100.0));
  EXPECT_EQ(close_frame(vol, off).params.fine_detail_strength, 0.0);
  for (bool on_gl : {true, false}) {
    const char* what = on_gl ? "GL" : "CPU";
    const FrameImages a = render(on_gl, vol, close_frame(vol, off)), b = render(on_gl, vol, f_on);
    const FrameImages z = render(on_gl, vol, close_frame(vol, zero)), e = render(on_gl, vol, close_frame(vol, sky));
    int cloud = 0;
    const double d = mean_diff_over_cloud(a.display, b.display, a.display, e.display, &cloud);
    std::cout << what << ": detail on vs off, mean |diff| over " << cloud << " cloud pixels " << d << " (display, 0..1), max "
              << max_abs_diff(a.display, b.display) << "\n";
    EXPECT_GT(cloud, kW * kH / 10) << what << ": a cloud to compare (12% of the view)";
    EXPECT_GT(d, 0.01) << what;
    EXPECT_EQ(max_abs_diff(a.linear, z.linear), 0.0) << what << ": strength 0 is off";
    EXPECT_EQ(max_abs_diff(a.display, z.display), 0.0) << what << ": strength 0 is off";
  }
}
