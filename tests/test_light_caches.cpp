// The lighting caches (gl_renderer.h, cpu_renderer.h): the light volume's optical depth follows the
// per-sample light march and the ground shadow map the per-pixel shadow march within stated bounds,
// on GL and on the CPU reference; each is rebuilt when the sun (or moving clouds) change it, never
// for a camera move alone, and moving clouds march per sample where a rebuild would not pay.
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

using testutil::lcg;

auto& render = testutil::render_on;  // render(on_gl, vol, frame)

}  // namespace

// With distance skipping the light volume marches only the texels a cloud sample can read (the
// field proves no density within one texel spacing of the rest: lighting.glsl light_volume_value):
// the image stays that of no skipping, GL and CPU, still and moving, while texels are spared.
// Texels wider than the field's cells (light_volume_scale 4, occupancy cells of 2 voxels) put
// empty radii between nothing and one spacing, where a bound that skips too eagerly shows. The
// moving frame's wind has no shear and no flow: its stretch is 1, so the field spares texels as
// when still (with the default shear and flow it spares none here: the radii, divided by the
// stretch, fall under the spacing).
TEST(LightCaches, LightVolumeMarchesOnlyTheTexelsSamplesRead) {
  for (double time : {0.0, 40.0}) {
    const PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 2, 2);
    RenderSettings s = with({"render.steps=128", "render.light_volume_scale=4", "motion.wind_speed=6",
                             "motion.wind_shear=0", "motion.flow_up=0", "motion.flow_forward=0"});
    s.time = time;
    const Camera cam = default_camera(vol, s, 60, kAspect);
    const Sun sun{default_sun(cam).azimuth_deg, 8.0};  // low: long shadows across the box, away from the cloud
    RenderSettings none = s, dist = s;
    none.skipping = Skipping::None;
    dist.skipping = Skipping::Distance;
    // A moving frame rebuilds the light volume only where that pays: force it here.
    const FrameSetup fn = make_frame(vol, none, cam, sun, time > 0 ? 1600 : 160, time > 0 ? 900 : 90);
    FrameSetup fd = make_frame(vol, dist, cam, sun, time > 0 ? 1600 : 160, time > 0 ? 900 : 90);
    ASSERT_EQ(fd.params.light_volume_on, 1.0) << "t " << time;
    ASSERT_EQ(fd.params.skip_distance, 1.0) << "t " << time;
    if (time > 0) {
      ASSERT_EQ(fd.params.motion_stretch, 1.0);
    }
    const std::vector<double> full = build_light_volume_cpu(vol, fn.params, &fn), sparse = build_light_volume_cpu(vol, fd.params, &fd);
    ASSERT_EQ(full.size(), sparse.size());
    size_t spared = 0;
    for (size_t i = 0; i < full.size(); ++i) {
      if (sparse[i] != full[i]) {
        ++spared;
        EXPECT_EQ(sparse[i], 0.0) << "a texel is either marched as before or left at 0";
      }
    }
    size_t zf = 0, zs = 0;
    for (size_t i = 0; i < full.size(); ++i) zf += full[i] == 0, zs += sparse[i] == 0;
    std::cout << "t " << time << ": light-volume texels spared " << spared << " of " << full.size() << " zeros " << zf << " / " << zs << "\n";
    EXPECT_GT(spared, 0u) << "t " << time << ": texels with light on them, left out (most others hold 0 anyway)";
    for (bool on_gl : {true, false}) {
      FrameSetup a = make_frame(vol, none, cam, sun, kW, kH), b = make_frame(vol, dist, cam, sun, kW, kH);
      for (FrameSetup* f : {&a, &b}) {  // the same per-frame grid as above at the test's size
        f->params.light_volume_on = 1.0;
        f->params.light_volume_dims = fd.params.light_volume_dims;
      }
      a.params = rounded_to_float(a.params), b.params = rounded_to_float(b.params);
      FrameImages ia = render(on_gl, vol, a), ib = render(on_gl, vol, b);
      const std::string what = std::string(on_gl ? "GL" : "CPU") + " t " + std::to_string(time);
      EXPECT_GT(image_stats(ia.display).stddev, 0.01) << what;
      EXPECT_EQ(max_abs_diff(ia.linear, ib.linear), 0.0) << what;
    }
  }
}

// The light volume's optical depth against the per-sample light march (CPU, double precision), at
// points inside the cloud: at the volume's resolution (scale 1) and at half of it (scale 2), the
// mean and the 99th-percentile |tau error| and the transmittance error exp(-tau) it makes.
TEST(LightCaches, LightVolumeFollowsTheLightMarch) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  Camera cam = default_camera(vol, 60, 16.0 / 9);
  double worst_mean[2] = {0, 0};
  for (int scale : {1, 2}) {
    RenderSettings s = with({"render.light_volume=true"});
    s.light_volume_scale = scale;
    FrameSetup f = make_frame(vol, s, cam, default_sun(cam), 16, 9);
    ASSERT_EQ(f.params.light_volume_on, 1.0);
    EXPECT_EQ(f.params.light_volume_dims.x, double((vol.dims[0] + scale - 1) / scale));
    std::vector<double> lv = build_light_volume_cpu(vol, f.params);
    // Exact at texel centres: the build is the march.
    glm::ivec3 n = glm::ivec3(f.params.light_volume_dims);
    glm::dvec3 centre = f.params.volume_min_m + (glm::dvec3(n / 2) + 0.5) / glm::dvec3(n) * f.params.volume_size_m;
    EXPECT_NEAR(reference_light_optical_depth(vol, f.params, centre, &lv),
                reference_light_optical_depth(vol, f.params, centre), 1e-9);
    uint32_t h = 99;
    std::vector<double> tau_err, t_err;
    double tau_sum = 0;
    for (int i = 0; tau_err.size() < 2000 && i < 200000; ++i) {
      glm::dvec3 u(lcg(h) / double(1 << 24), lcg(h) / double(1 << 24), lcg(h) / double(1 << 24));
      glm::ivec3 v = glm::min(glm::ivec3(u * glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2])),
                              glm::ivec3(vol.dims[0] - 1, vol.dims[1] - 1, vol.dims[2] - 1));
      if (vol.rgba[((size_t(v.z) * vol.dims[1] + v.y) * vol.dims[0] + v.x) * 4] <= 0.05f) continue;  // in the cloud
      glm::dvec3 p = f.params.volume_min_m + u * f.params.volume_size_m;
      double march = reference_light_optical_depth(vol, f.params, p);
      double look = reference_light_optical_depth(vol, f.params, p, &lv);
      tau_err.push_back(std::abs(look - march));
      t_err.push_back(std::abs(std::exp(-look) - std::exp(-march)));
      tau_sum += march;
    }
    ASSERT_GE(tau_err.size(), 1000u);
    double mean = 0, tmean = 0;
    for (double e : tau_err) mean += e / double(tau_err.size());
    for (double e : t_err) tmean += e / double(t_err.size());
    std::sort(tau_err.begin(), tau_err.end());
    std::sort(t_err.begin(), t_err.end());
    double p99 = tau_err[tau_err.size() * 99 / 100], t99 = t_err[t_err.size() * 99 / 100];
    std::cout << "light volume scale " << scale << ": mean tau " << tau_sum / double(tau_err.size()) << ", |tau error| mean "
              << mean << " p99 " << p99 << "; |T error| mean " << tmean << " p99 " << t99 << "\n";
    worst_mean[scale - 1] = mean;
    // Bounds (measured, then about 2x headroom; see docs/viewer-speed.md): the light march's own
    // first step is 2.5 voxels, so interpolating between texel centres a voxel or two apart errs
    // by a fraction of a voxel's optical depth (sigma_t * voxel = 0.5 at density 1).
    EXPECT_LT(tmean, scale == 1 ? 0.02 : 0.04) << "scale " << scale;
    EXPECT_LT(t99, scale == 1 ? 0.10 : 0.20) << "scale " << scale;
  }
  EXPECT_LT(worst_mean[0], worst_mean[1]) << "a finer light volume is closer to the march";
  // A large field gets a coarser grid instead of gigabytes: 512 x 64 x 512 voxels at scale 1 would be
  // 16.8 M texels; the scale doubles to 2 (2.1 M).
  PreparedVolume big;
  big.dims = {512, 64, 512};
  big.voxel_size = 10;
  big.occ_dims = {64, 8, 64};
  RenderSettings s1 = with({"render.light_volume=true", "render.light_volume_scale=1"});
  FrameSetup fb = make_frame(big, s1, cam, default_sun(cam), 16, 9);
  EXPECT_EQ(fb.params.light_volume_dims, glm::dvec3(256, 32, 256));
  EXPECT_LE(fb.params.light_volume_dims.x * fb.params.light_volume_dims.y * fb.params.light_volume_dims.z,
            double(kMaxLightVolumeTexels));
}

// The light volume is rebuilt when the sun, the volume or a lighting key changes, never when only
// the camera moves (a counter, not a timing); the GL image with it matches the CPU reference's.
TEST(LightCaches, LightVolumeRebuildsOnSunChangeNotOnCameraMove) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  RenderSettings s = with({"render.light_volume=true", "render.exact_filter=true", "render.steps=96"});
  Camera cam = default_camera(vol, 60, kAspect);
  Sun sun = default_sun(cam);
  EXPECT_EQ(r.stats().light_volume_builds, 0);
  FrameSetup f = make_frame(vol, s, cam, sun, kW, kH);
  r.render(f);
  EXPECT_EQ(r.stats().light_volume_builds, 1);
  FrameImages a = r.read_back();
  FrameImages ref = render_cpu(vol, f);
  double p = psnr(a.display, ref.display);
  std::cout << "light volume: PSNR GL vs CPU (exact filter) " << p << " dB\n";
  EXPECT_GT(p, 50.0);
  Camera moved = cam;
  for (int i = 1; i <= 3; ++i) {
    moved.eye += glm::dvec3(37.0 * i, 11.0, -23.0);
    r.render(make_frame(vol, s, moved, sun, kW, kH));
  }
  EXPECT_EQ(r.stats().light_volume_builds, 1) << "camera moves alone keep the light volume";
  Sun later = sun;
  later.elevation_deg += 5;
  r.render(make_frame(vol, s, moved, later, kW, kH));
  EXPECT_EQ(r.stats().light_volume_builds, 2) << "a new sun rebuilds it";
  RenderSettings denser = s;
  denser.density = 2;
  r.render(make_frame(vol, denser, moved, later, kW, kH));
  EXPECT_EQ(r.stats().light_volume_builds, 3) << "a lighting key rebuilds it";
  r.render(make_frame(vol, denser, moved, later, 320, 180));
  EXPECT_EQ(r.stats().light_volume_builds, 3) << "a new viewport size does not";
  r.set_volume(vol);
  r.render(make_frame(vol, denser, moved, later, 320, 180));
  EXPECT_EQ(r.stats().light_volume_builds, 4) << "a new volume rebuilds it";
  RenderSettings off = denser;
  off.light_volume = false;
  r.render(make_frame(vol, off, moved, later, 320, 180));
  EXPECT_EQ(r.stats().light_volume_builds, 4) << "off: never built";
}

// Moving clouds: the light volume spans the march box and is rebuilt every frame from the moving
// density, where the grid has no more texels than the frame has pixels (make_frame). Then GL and
// the CPU reference agree, the volume is as close to the per-sample march as a still frame's is to
// its own, it follows the time (a new time rebuilds it, a camera move alone does not), and a
// frame smaller than the grid marches per sample.
TEST(LightCaches, MovingCloudsRebuildTheLightVolumeWhereItPays) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  RenderSettings s = with({"render.light_volume=true", "render.light_volume_scale=4", "render.exact_filter=true",
                           "render.steps=96", "render.shadow_map=false"});
  s.motion.wind_speed = 6.0;
  const int w = 240, h = 135;
  Camera cam = default_camera(vol, 60, double(w) / h);
  Sun sun = default_sun(cam);
  auto frame = [&](const RenderSettings& rs, double t, const Camera& c, int fw, int fh) {
    RenderSettings x = rs;
    x.time = t;
    return make_frame(vol, x, c, sun, fw, fh);
  };
  FrameSetup moving = frame(s, 95.0, cam, w, h);
  ASSERT_EQ(moving.params.motion_on, 1.0);
  ASSERT_EQ(moving.params.light_volume_on, 1.0) << "a grid smaller than the frame is rebuilt per frame";
  const glm::dvec3 dims = moving.params.light_volume_dims, still_dims = frame(s, 0.0, cam, w, h).params.light_volume_dims;
  EXPECT_GT(dims.x * dims.y * dims.z, still_dims.x * still_dims.y * still_dims.z) << "it spans the grown march box";
  EXPECT_LE(dims.x * dims.y * dims.z, double(w) * h);
  // The rule: a frame with fewer pixels than the grid's texels marches per sample.
  const int small_w = 64, small_h = 36;
  ASSERT_GT(dims.x * dims.y * dims.z, double(small_w) * small_h);
  EXPECT_EQ(frame(s, 95.0, cam, small_w, small_h).params.light_volume_on, 0.0);
  RenderSettings temporal = s;
  temporal.temporal = true;  // marches a sixteenth of the pixels
  EXPECT_EQ(frame(temporal, 95.0, cam, w, h).params.light_volume_on, 0.0);
  EXPECT_EQ(frame(temporal, 95.0, cam, 4 * w, 4 * h).params.light_volume_on, 1.0);

  r.render(moving);
  EXPECT_EQ(r.stats().light_volume_builds, 1);
  FrameImages gl = r.read_back();
  FrameImages cpu = render_cpu(vol, moving);
  const double p = psnr(gl.display, cpu.display);
  EXPECT_GT(p, 50.0) << "GL and the CPU reference build and read the same moving light volume";

  // Against the per-sample march of the same frame, beside the still frame's light volume against its march.
  RenderSettings march = s;
  march.light_volume = false;
  const double moving_err = rmse(cpu.display, render_cpu(vol, frame(march, 95.0, cam, w, h)).display);
  const double still_err =
      rmse(render_cpu(vol, frame(s, 0.0, cam, w, h)).display, render_cpu(vol, frame(march, 0.0, cam, w, h)).display);
  std::cout << "moving light volume: PSNR GL vs CPU " << p << " dB; RMSE against the march " << moving_err
            << " (still: " << still_err << ")\n";
  EXPECT_GT(moving_err, 0.0) << "the lookup, not the march, lit the frame";
  EXPECT_LT(moving_err, 2.0 * still_err + 1e-3);

  Camera moved = cam;
  moved.eye += glm::dvec3(41.0, 7.0, -29.0);
  r.render(frame(s, 95.0, moved, w, h));
  EXPECT_EQ(r.stats().light_volume_builds, 1) << "a camera move at the same time keeps it";
  r.render(frame(s, 95.0 + 1.0 / 24.0, moved, w, h));
  EXPECT_EQ(r.stats().light_volume_builds, 2) << "the next frame's time rebuilds it";
  r.render(frame(s, 95.0 + 1.0 / 24.0, moved, small_w, small_h));
  EXPECT_EQ(r.stats().light_volume_builds, 2) << "a small frame marches and builds nothing";
}

// render.shadow_map: the ground's cloud shadow from a 2D map of the ground pass's own march. At a
// texel centre the lookup is the march; between, bilinear; a ground point outside the map's area
// sends its sun ray past the march box, where the march gives exactly 1 (so the area is not too
// small); the map holds a real shadow. A finer map is closer.
TEST(LightCaches, ShadowMapFollowsTheShadowMarch) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  Camera cam = default_camera(vol, 60, 16.0 / 9);
  double mean_err[2] = {0, 0};
  for (int scale : {1, 2}) {
    RenderSettings s = with({"render.shadow_map=true"});
    s.shadow_map_scale = scale;
    const Sun sun{210, 40};
    FrameSetup f = make_frame(vol, s, cam, sun, 16, 9);
    ASSERT_EQ(f.params.shadow_map_on, 1.0);
    const std::vector<double> map = build_shadow_map_cpu(vol, f);
    ASSERT_EQ(map.size(), size_t(f.params.shadow_map_nx * f.params.shadow_map_nz));
    EXPECT_LT(*std::min_element(map.begin(), map.end()), 0.5) << "the blob casts a shadow";
    const glm::dvec2 lo(f.params.march_min_m.x + f.params.shadow_map_min_x_m, f.params.march_min_m.z + f.params.shadow_map_min_z_m);
    const double texel = f.params.shadow_map_texel_m;
    EXPECT_NEAR(texel, vol.voxel_size * scale, 1e-3);
    const glm::dvec2 size = glm::dvec2(f.params.shadow_map_nx, f.params.shadow_map_nz) * texel;
    auto ground = [&](glm::dvec2 xz) { return glm::dvec3(xz.x, f.params.ground_y_m, xz.y); };
    // Exact at texel centres.
    for (glm::ivec2 t : {glm::ivec2(0, 0), glm::ivec2(int(f.params.shadow_map_nx) / 2, int(f.params.shadow_map_nz) / 3)}) {
      const glm::dvec3 c = ground(lo + (glm::dvec2(t) + 0.5) * texel);
      EXPECT_NEAR(reference_ground_shadow(vol, f, c, &map), reference_ground_shadow(vol, f, c), 1e-6);
    }
    // Random ground points over twice the map's area.
    uint32_t h = 7;
    std::vector<double> err;
    int outside = 0;
    for (int i = 0; i < 4000; ++i) {
      const glm::dvec2 u(lcg(h) / double(1 << 24), lcg(h) / double(1 << 24));
      const glm::dvec3 p = ground(lo - 0.5 * size + u * 2.0 * size);
      const double march = reference_ground_shadow(vol, f, p), look = reference_ground_shadow(vol, f, p, &map);
      const glm::dvec2 x = (glm::dvec2(p.x, p.z) - lo) / texel;
      if (x.x < 0 || x.y < 0 || x.x > f.params.shadow_map_nx || x.y > f.params.shadow_map_nz) {
        ++outside;
        EXPECT_EQ(march, 1.0) << "a ray from outside the map's area crosses the box at " << x.x << ", " << x.y;
        EXPECT_EQ(look, 1.0);
      } else {
        err.push_back(std::abs(look - march));
      }
    }
    ASSERT_GT(outside, 1000);
    ASSERT_GT(err.size(), 500u);
    double mean = 0;
    for (double e : err) mean += e / double(err.size());
    std::sort(err.begin(), err.end());
    const double p99 = err[err.size() * 99 / 100];
    std::cout << "shadow map scale " << scale << " (" << f.params.shadow_map_nx << " x " << f.params.shadow_map_nz
              << " texels of " << texel << " m): |T error| mean " << mean << " p99 " << p99 << "\n";
    mean_err[scale - 1] = mean;
    // Bounds: measured (0.0007 / 0.0025 mean, 0.018 / 0.071 p99), then about 2x headroom.
    EXPECT_LT(mean, scale == 1 ? 0.002 : 0.006) << "scale " << scale;
    EXPECT_LT(p99, scale == 1 ? 0.04 : 0.15) << "scale " << scale;
  }
  EXPECT_LT(mean_err[0], mean_err[1]) << "a finer map is closer to the march";
  // Off in layer mode, with the sun below the horizon and without the ground.
  const PreparedVolume tiling = prepare_volume(testutil::synthetic("noise"), 8);
  EXPECT_EQ(make_frame(tiling, with({"render.shadow_map=true"}), cam, Sun{210, 40}, 16, 9).params.shadow_map_on, 1.0);
  EXPECT_EQ(make_frame(tiling, with({"render.shadow_map=true", "render.mode=layer"}), cam, Sun{210, 40}, 16, 9).params.shadow_map_on, 0.0);
  EXPECT_EQ(make_frame(vol, with({"render.shadow_map=true"}), cam, Sun{210, -5}, 16, 9).params.shadow_map_on, 0.0);
  EXPECT_EQ(make_frame(vol, with({"render.shadow_map=true", "render.ground=false"}), cam, Sun{210, 40}, 16, 9).params.shadow_map_on, 0.0);
}

// The shadow map is rebuilt when the sun, the volume, the time (moving clouds) or a lighting key
// changes, never when only the camera moves; the GL image with it is the CPU reference's, and
// differs from the per-pixel march only at the shadows' edges.
TEST(LightCaches, ShadowMapRebuildsOnSunChangeNotOnCameraMove) {
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(vol);
  RenderSettings s = with({"render.shadow_map=true", "render.steps=96"});
  Camera cam = default_camera(vol, 60, kAspect);
  const Sun sun{210, 40};
  FrameSetup f = make_frame(vol, s, cam, sun, kW, kH);
  r.render(f);
  EXPECT_EQ(r.stats().shadow_map_builds, 1);
  const FrameImages a = r.read_back();
  const double p = psnr(a.display, render_cpu(vol, f).display);
  std::cout << "shadow map: PSNR GL vs CPU " << p << " dB\n";
  EXPECT_GT(p, 50.0);
  RenderSettings march = s;
  march.shadow_map = false;
  const FrameImages m = render_gl(vol, make_frame(vol, march, cam, sun, kW, kH));
  const double e = rmse(a.display, m.display), d = max_abs_diff(a.display, m.display);
  std::cout << "shadow map against the per-pixel march: RMSE " << e << ", max |diff| " << d << "\n";
  EXPECT_GT(d, 0.0) << "the lookup was not used";
  EXPECT_LT(e, 0.003);
  Camera moved = cam;
  for (int i = 1; i <= 3; ++i) {
    moved.eye += glm::dvec3(37.0 * i, 11.0, -23.0);
    r.render(make_frame(vol, s, moved, sun, kW, kH));
  }
  EXPECT_EQ(r.stats().shadow_map_builds, 1) << "camera moves alone keep the map";
  r.render(make_frame(vol, s, moved, Sun{210, 45}, kW, kH));
  EXPECT_EQ(r.stats().shadow_map_builds, 2) << "a new sun rebuilds it";
  RenderSettings denser = s;
  denser.density = 2;
  r.render(make_frame(vol, denser, moved, Sun{210, 45}, kW, kH));
  EXPECT_EQ(r.stats().shadow_map_builds, 3) << "a lighting key rebuilds it";
  RenderSettings light_keys = denser;
  light_keys.light_samples = 9;  // the light march's, not the shadow march's
  r.render(make_frame(vol, light_keys, moved, Sun{210, 45}, kW, kH));
  EXPECT_EQ(r.stats().shadow_map_builds, 3) << "a key of the light march alone does not";
  r.render(make_frame(vol, denser, moved, Sun{210, 45}, 320, 180));
  EXPECT_EQ(r.stats().shadow_map_builds, 3) << "a new viewport size does not";
  RenderSettings moving = denser;
  apply_setting(moving, "motion.wind_speed=20");
  for (double t : {10.0, 11.0}) {
    moving.time = t;
    FrameSetup fm = make_frame(vol, moving, moved, Sun{210, 45}, 640, 360);
    ASSERT_EQ(fm.params.shadow_map_on, 1.0);
    r.render(fm);
  }
  EXPECT_EQ(r.stats().shadow_map_builds, 5) << "moving clouds rebuild it every frame";
  // ...so they march per pixel instead while the map has over a quarter of the frame's pixels
  // (125 x 146 texels; 160 x 90 pixels); still clouds always use it.
  FrameSetup small = make_frame(vol, moving, moved, Sun{210, 45}, kW, kH);
  EXPECT_GT(small.params.motion_on, 0.5);
  EXPECT_EQ(small.params.shadow_map_on, 0.0);
  EXPECT_EQ(make_frame(vol, denser, moved, Sun{210, 45}, kW, kH).params.shadow_map_on, 1.0);
  r.render(small);
  EXPECT_EQ(r.stats().shadow_map_builds, 5);
  r.set_volume(vol);
  r.render(make_frame(vol, denser, moved, Sun{210, 45}, 320, 180));
  EXPECT_EQ(r.stats().shadow_map_builds, 6) << "a new volume rebuilds it";
  RenderSettings off = denser;
  off.shadow_map = false;
  r.render(make_frame(vol, off, moved, Sun{210, 45}, 320, 180));
  EXPECT_EQ(r.stats().shadow_map_builds, 6) << "off: never built";
  // The frame line reports a build when there is one: once over two still frames, never when off.
  auto reports = [](const char* set) {
    std::ostringstream out, err;
    EXPECT_EQ(run_cli({"cloudviewer", "synthetic:blob", "--headless", "--size", "32x18", "--frames", "2", "--fps", "0",
                       "--set", set, "--out", (std::filesystem::temp_directory_path() / "cv_shadow_%d.png").string()},
                      out, err), 0) << err.str();
    int n = 0;
    for (size_t at = out.str().find("gpu: ground shadow map "); at != std::string::npos;
         at = out.str().find("gpu: ground shadow map ", at + 1))
      ++n;
    return n;
  };
  EXPECT_EQ(reports("render.shadow_map=true"), 1);
  EXPECT_EQ(reports("render.shadow_map=false"), 0);
}
