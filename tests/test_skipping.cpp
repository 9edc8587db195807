// Empty-space skipping (distance_field.h, prepared_volume.h): the distance field of the coarse grid
// is exact (so conservative), distance and thesis skipping leave the image bit for bit unchanged on
// GL and on the CPU reference while doing less work, still or moving, eroded or not, on tiling
// volumes with partial cells; the occupancy cell grows with the volume only.
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

auto& render = testutil::render_on;  // render(on_gl, vol, frame)

double loop_trips(bool on_gl, const PreparedVolume& vol, RenderSettings s, const Camera& cam, int w, int h) {
  s.output = OutputMode::Iterations;
  return testutil::loop_trips_sum(render(on_gl, vol, make_frame(vol, s, cam, default_sun(cam), w, h)));
}

using testutil::lcg;

// 60 voxels of density 1 at random places of a 64^3 box of 10 m voxels (the rest empty): what a
// skipping radius one voxel too long gets wrong.
cloudgen::Volume isolated_voxels(uint32_t seed) {
  cloudgen::Volume sparse;
  sparse.dims = {64, 64, 64};
  sparse.voxel_size = 10;
  sparse.origin = {-320, 200, -320};
  sparse.density.assign(sparse.voxel_count(), 0.f);
  uint32_t h = seed;
  for (int i = 0; i < 60; ++i) {
    uint32_t x = lcg(h) % 64, y = lcg(h) % 64, z = lcg(h) % 64;
    sparse.density[sparse.index(x, y, z)] = 1.f;
  }
  return sparse;
}

// A volume, its settings and a camera for the skipping comparisons.
struct SkipCase {
  const char* name;
  PreparedVolume vol;
  RenderSettings s;
  Camera cam;
};

// Brute force: the L-infinity cell distance from every cell to the nearest set cell, wrapping x and
// z when asked; 255 when there is none (the field's cap).
std::vector<int> brute_distance(const std::vector<uint8_t>& occ, const std::array<int, 3>& n, bool wrap) {
  std::vector<int> d(occ.size(), 255);
  auto axis = [&](int a, int b, int len, bool w) {
    int diff = std::abs(a - b);
    return w ? std::min(diff, len - diff) : diff;
  };
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x)
        for (int oz = 0; oz < n[2]; ++oz)
          for (int oy = 0; oy < n[1]; ++oy)
            for (int ox = 0; ox < n[0]; ++ox) {
              if (!occ[(size_t(oz) * n[1] + oy) * n[0] + ox]) continue;
              int dist = std::max({axis(x, ox, n[0], wrap), axis(y, oy, n[1], false), axis(z, oz, n[2], wrap)});
              int& cell = d[(size_t(z) * n[1] + y) * n[0] + x];
              cell = std::min(cell, dist);
            }
  return d;
}

}  // namespace

// The separable transform on grids larger than the strided passes' 16-line tiles (widths that are
// no multiple of 16, lines of odd and even lengths, wrapped over half a line each side), with few
// set cells so distances run long, and one empty grid: against the distance to each set cell.
TEST(Skipping, DistanceFieldIsExactOnLargeSparseGrids) {
  uint32_t h = 77;
  for (int trial = 0; trial < 6; ++trial) {
    const std::array<int, 3> n{{int(17 + lcg(h) % 40), int(5 + lcg(h) % 30), int(17 + lcg(h) % 40)}};
    std::vector<uint8_t> occ(static_cast<size_t>(n[0]) * n[1] * n[2], 0);
    std::vector<std::array<int, 3>> set;
    const int points = trial == 0 ? 0 : 1 + int(lcg(h) % 6);
    for (int i = 0; i < points; ++i) {
      const std::array<int, 3> q{{int(lcg(h) % n[0]), int(lcg(h) % n[1]), int(lcg(h) % n[2])}};
      occ[(size_t(q[2]) * n[1] + q[1]) * n[0] + q[0]] = 1;
      set.push_back(q);
    }
    const std::array<int, 3> dims{{n[0] * 2, n[1] * 2, n[2] * 2}};
    for (bool tiles : {false, true}) {
      const std::vector<uint8_t> field = occupancy_distance(occ, n, tiles, dims, 2);
      for (int z = 0; z < n[2]; ++z)
        for (int y = 0; y < n[1]; ++y)
          for (int x = 0; x < n[0]; ++x) {
            int best = 255;
            for (const auto& q : set) {
              auto ax = [&](int a, int b, int len, bool w) { const int d = std::abs(a - b); return w ? std::min(d, len - d) : d; };
              best = std::min(best, std::max({ax(x, q[0], n[0], tiles), ax(y, q[1], n[1], false), ax(z, q[2], n[2], tiles)}));
            }
            ASSERT_EQ(int(field[(size_t(z) * n[1] + y) * n[0] + x]), best)
                << "trial " << trial << " tiles " << tiles << " cell " << x << "," << y << "," << z;
          }
    }
  }
}

// The field is the exact L-infinity distance (so no cell within distance d of a set cell is ever
// reported farther than d), on small random grids, with and without x/z wrapping; a tiling volume
// whose cells do not divide it is checked in voxels (its last cell is partial).
TEST(Skipping, DistanceFieldIsExactAndConservative) {
  uint32_t h = 2024;
  for (int trial = 0; trial < 12; ++trial) {
    std::array<int, 3> n{{int(3 + lcg(h) % 9), int(2 + lcg(h) % 7), int(3 + lcg(h) % 9)}};
    const int cell = 4;
    std::array<int, 3> dims{{n[0] * cell, n[1] * cell, n[2] * cell}};
    std::vector<uint8_t> occ(static_cast<size_t>(n[0]) * n[1] * n[2], 0);
    const uint32_t percent = trial == 0 ? 0 : 1 + lcg(h) % 12;  // trial 0: nothing set at all
    for (uint8_t& o : occ) o = lcg(h) % 100 < percent ? 1 : 0;
    for (bool tiles : {false, true}) {
      std::vector<uint8_t> field = occupancy_distance(occ, n, tiles, dims, cell);
      std::vector<int> truth = brute_distance(occ, n, tiles);
      ASSERT_EQ(field.size(), truth.size());
      int farthest = 0;
      for (size_t i = 0; i < field.size(); ++i) {
        ASSERT_LE(int(field[i]), truth[i]) << "never farther than the nearest set cell: trial " << trial << " cell " << i;
        ASSERT_EQ(int(field[i]), truth[i]) << "trial " << trial << " cell " << i << " tiles " << tiles;
        EXPECT_EQ(field[i] == 0, occ[i] != 0);
        farthest = std::max(farthest, int(field[i]));
      }
      if (trial > 0) {
        EXPECT_GE(farthest, 1);
      }
    }
    // A partial last cell on a wrapping axis (1 to 3 voxels short in x, 0 to 3 in z): counted in
    // cells a route across the seam is up to one cell too long, so check the field in voxels. No
    // occupied cell may lie within (d - 1) cells of any point of a cell at distance d (L-infinity,
    // wrapping at the tile's period), and the field is at least one less than the wrapped count.
    const std::array<int, 3> odd{{dims[0] - 1 - int(lcg(h) % 3), dims[1], dims[2] - int(lcg(h) % 4)}};
    const std::vector<uint8_t> field = occupancy_distance(occ, n, true, odd, cell);
    const std::vector<int> wrapped = brute_distance(occ, n, true);
    auto gap = [&](int a, int b, int axis) {  // voxels between cell a's and cell b's extents on one axis
      const int len = odd[size_t(axis)];
      const int a0 = a * cell, a1 = std::min(a0 + cell, len), b0 = b * cell, b1 = std::min(b0 + cell, len);
      const int plain = std::max(0, std::max(a0, b0) - std::min(a1, b1));
      if (axis == 1) return plain;
      return std::min(plain, std::max(0, std::min(a0, b0) + len - std::max(a1, b1)));
    };
    int beyond_one = 0;
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const size_t i = (size_t(z) * n[1] + y) * n[0] + x;
          ASSERT_EQ(field[i] == 0, occ[i] != 0) << "trial " << trial;
          if (occ[i]) continue;
          ASSERT_GE(int(field[i]), std::max(1, wrapped[i] - 1)) << "trial " << trial << " cell " << i;
          beyond_one += field[i] > 1;
          for (int oz = 0; oz < n[2]; ++oz)
            for (int oy = 0; oy < n[1]; ++oy)
              for (int ox = 0; ox < n[0]; ++ox) {
                if (!occ[(size_t(oz) * n[1] + oy) * n[0] + ox]) continue;
                const int g = std::max({gap(x, ox, 0), gap(y, oy, 1), gap(z, oz, 2)});
                ASSERT_LE((int(field[i]) - 1) * cell, g) << "trial " << trial << " cell " << i;
              }
        }
    if (trial == 0) {
      EXPECT_GT(beyond_one, 0) << "an empty grid is far from everything";
    }
  }
  // And prepare_volume fills it from the cells holding density (before padding).
  PreparedVolume vol = prepare_volume(testutil::synthetic("blob"), 8, 2);
  ASSERT_EQ(vol.dist.size(), vol.occ.size());
  size_t far = 0;
  for (size_t i = 0; i < vol.dist.size(); ++i) {
    if (vol.dist[i] >= 2) ++far;
    if (vol.dist[i] <= 2) {
      EXPECT_EQ(vol.occ[i], 1) << "padding 2 covers every cell within 2 of density";
    }
  }
  EXPECT_GT(far, 0u);
}

// Distance skipping keeps exactly the samples of the plain march: max |diff| = 0 (bit for bit), on
// GL and on the CPU reference, with the light and shadow marches skipping by the field too, and
// fewer loop trips. The isolated-voxel volume at grazing angles is what a radius one voxel too long
// gets wrong: a field that claims one more cell than it proves shows up as a difference.
TEST(Skipping, DistanceSkippingDoesNotChangeTheImage) {
  const cloudgen::Volume sparse = isolated_voxels(12345);
  std::vector<SkipCase> cases;
  {
    PreparedVolume v = prepare_volume(testutil::synthetic("blob"), 8, 2);
    Camera cam = default_camera(v, 60, kAspect);
    cases.push_back({"blob", v, with({"render.steps=128"}), cam});
  }
  {
    PreparedVolume v = prepare_volume(sparse, 4, 1);
    Camera cam;
    cam.eye = v.center() + glm::dvec3(250, 180, -700);
    cam.target = v.center();
    cases.push_back({"isolated voxels", v, with({"render.sigma_t=0.5", "render.steps=256"}), cam});
  }
  for (const SkipCase& c : cases)
    for (bool on_gl : {true, false}) {
      std::string what = std::string(c.name) + (on_gl ? " GL" : " CPU");
      RenderSettings none = c.s, dist = c.s, dist_light = c.s;
      none.skipping = Skipping::None;
      dist.skipping = Skipping::Distance;
      dist_light.skipping = Skipping::Distance;
      dist_light.occupancy_light = true;
      Sun sun = default_sun(c.cam);
      FrameImages a = render(on_gl, c.vol, make_frame(c.vol, none, c.cam, sun, kW, kH));
      FrameImages b = render(on_gl, c.vol, make_frame(c.vol, dist, c.cam, sun, kW, kH));
      FrameImages l = render(on_gl, c.vol, make_frame(c.vol, dist_light, c.cam, sun, kW, kH));
      EXPECT_GT(image_stats(a.display).stddev, 0.01) << what << ": a picture to compare";
      EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << what;
      EXPECT_EQ(max_abs_diff(a.display, b.display), 0.0) << what;
      EXPECT_EQ(max_abs_diff(a.linear, l.linear), 0.0) << what << " (light and shadow marches by the field)";
      double ta = loop_trips(on_gl, c.vol, none, c.cam, kW, kH), tb = loop_trips(on_gl, c.vol, dist, c.cam, kW, kH);
      RenderSettings thesis = c.s;
      thesis.skipping = Skipping::Thesis;
      double tt = loop_trips(on_gl, c.vol, thesis, c.cam, kW, kH);
      std::cout << what << ": loop trips none / thesis / distance " << ta << " / " << tt << " / " << tb << "\n";
      EXPECT_LT(tb, 0.8 * ta) << what;
      EXPECT_LT(tb, tt) << what << ": the field jumps farther than one cell";
      // Sensitivity: a radius one cell longer than the field proves changes the image.
      if (std::string(c.name) == "isolated voxels") {
        FrameSetup bad = make_frame(c.vol, dist, c.cam, sun, kW, kH);
        bad.params.df_margin_m -= bad.params.df_cell_m;
        EXPECT_GT(max_abs_diff(a.linear, render(on_gl, c.vol, bad).linear), 0.01) << what << ": the check can fail";
      }
    }
  // render.occupancy=false still means no skipping, whatever render.skipping says.
  RenderSettings s = with({"render.occupancy=false", "render.skipping=distance"});
  FrameSetup f = make_frame(cases[0].vol, s, cases[0].cam, default_sun(cases[0].cam), 16, 9);
  EXPECT_EQ(f.params.occupancy_skip, 0.0);
  EXPECT_EQ(f.params.skip_distance, 0.0);
  EXPECT_EQ(RenderSettings{}.skipping, Skipping::Distance);
}

// Moving clouds (box mode) jump by the still distance field, read at the static point seen and
// shortened by the motion's stretch (lighting.glsl empty_radius_of): the same image as no
// skipping, bit for bit, on GL and the CPU reference, with fewer loop trips than the thesis scheme
// on the moved grid (isolated voxels: half the trips the moved grid's own field took, 3.13 M).
// A field one cell longer than the volume proves changes the image: the check can fail. (Jumps not
// shortened by the stretch change nothing at these times; the moving-layer test below shows the
// stretch is needed, through the same empty_radius_of.)
TEST(Skipping, DistanceSkippingStaysExactWhileMoving) {
  const cloudgen::Volume sparse = isolated_voxels(777);
  std::vector<SkipCase> cases;
  {
    PreparedVolume v = prepare_volume(testutil::synthetic("blob"), 4, 2);
    RenderSettings s = with({"render.steps=128", "motion.wind_speed=6", "motion.wind_shear=3"});
    s.time = 40;  // tops 960 m downwind, the base 240 m: still in view, strongly sheared
    cases.push_back({"blob", v, s, default_camera(v, 70, kAspect)});
  }
  {
    PreparedVolume v = prepare_volume(sparse, 4, 1);
    RenderSettings s = with({"render.sigma_t=0.5", "render.steps=256", "motion.wind_speed=4"});
    s.time = 30;
    Camera cam;
    cam.eye = v.center() + glm::dvec3(250, 180, -700);
    cam.target = v.center();
    cases.push_back({"isolated voxels", v, s, cam});
  }
  for (const SkipCase& c : cases)
    for (bool on_gl : {true, false}) {
      std::string what = std::string(c.name) + (on_gl ? " GL" : " CPU");
      RenderSettings none = c.s, dist = c.s, thesis = c.s;
      none.skipping = Skipping::None;
      dist.skipping = Skipping::Distance;
      thesis.skipping = Skipping::Thesis;
      Sun sun = default_sun(c.cam);
      FrameSetup fd = make_frame(c.vol, dist, c.cam, sun, kW, kH);
      ASSERT_EQ(fd.params.motion_on, 1.0) << what;
      ASSERT_EQ(fd.params.skip_distance, 1.0) << what;
      ASSERT_GT(fd.params.motion_stretch, 1.2) << what << ": a stretch that matters";
      // Nothing reads the moved grid here (make_frame leaves it unbuilt): the exactness below holds
      // without it, on GL with the still grid bound in its place.
      ASSERT_TRUE(fd.moved_occupancy.empty()) << what;
      FrameImages a = render(on_gl, c.vol, make_frame(c.vol, none, c.cam, sun, kW, kH));
      FrameImages b = render(on_gl, c.vol, fd);
      EXPECT_GT(image_stats(a.display).stddev, 0.01) << what << ": a picture to compare";
      RenderSettings seen = none;
      seen.output = OutputMode::Transmittance;
      EXPECT_LT(image_stats(render(on_gl, c.vol, make_frame(c.vol, seen, c.cam, sun, kW, kH)).linear).min, 0.5)
          << what << ": the cloud in view";
      EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << what;
      EXPECT_EQ(max_abs_diff(a.display, b.display), 0.0) << what;
      const double ta = loop_trips(on_gl, c.vol, none, c.cam, kW, kH), tb = loop_trips(on_gl, c.vol, dist, c.cam, kW, kH),
                   tt = loop_trips(on_gl, c.vol, thesis, c.cam, kW, kH);
      std::cout << what << " (moving): loop trips none / thesis / distance " << ta << " / " << tt << " / " << tb << "\n";
      EXPECT_LT(tb, (std::string(c.name) == "blob" ? 0.5 : 0.9) * ta) << what;
      EXPECT_LT(tb, tt) << what << ": the field jumps farther than the thesis's large step";
      FrameSetup unshortened = fd;
      unshortened.params.motion_stretch = 1.0;
      const double lie_stretch = max_abs_diff(a.linear, render(on_gl, c.vol, unshortened).linear);
      PreparedVolume longer = c.vol;  // every distance one cell longer
      for (uint8_t& d : longer.dist) d = uint8_t(std::min(255, d + 1));
      const double lie_field = max_abs_diff(a.linear, render(on_gl, longer, fd).linear);
      std::cout << what << ": jumps not shortened change the image by " << lie_stretch
                << ", a field one cell longer by " << lie_field << "\n";
      if (std::string(c.name) == "isolated voxels") {
        EXPECT_GT(lie_field, 0.01) << what << ": the check can fail";
      }
    }
}

// The bound behind the eroded field (cloudgen/erosion.glsl erosion_bound): wherever a trilinear
// mix of eight texels, seen at a height in [h0, h1], keeps density after erosion, one of the eight
// has a bound above zero. Random texels, weights and heights, near the threshold on purpose.
TEST(Skipping, ErosionBoundHoldsForEveryTrilinearMix) {
  namespace eg = cloudgen::erosion_glsl;
  uint32_t h = 99;
  auto unit = [&h] { return double(lcg(h) % 100001) / 100000.0; };
  int positive = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    const double erosion = 0.05 + 0.9 * unit();
    const double h0 = 0.3 * unit() - 0.05, h1 = h0 + 0.1 * unit();
    double base[8], g[8], b[8], a[8], w[8], sum = 0;
    for (int k = 0; k < 8; ++k) {
      base[k] = 0.6 * unit(), g[k] = unit(), b[k] = unit(), a[k] = unit();
      w[k] = unit();
      sum += w[k];
    }
    double mb = 0, mg = 0, mbl = 0, ma = 0, best = -1e9;
    for (int k = 0; k < 8; ++k) {
      mb += w[k] / sum * base[k], mg += w[k] / sum * g[k], mbl += w[k] / sum * b[k], ma += w[k] / sum * a[k];
      best = std::max(best, eg::erosion_bound(base[k], eg::erosion_detail(g[k], b[k], a[k]), h0, h1, erosion));
    }
    const double seen = h0 + (h1 - h0) * unit();
    const double kept = cloudgen::eroded_density(mb, mg, mbl, ma, seen, erosion);
    if (kept > 0) {
      ++positive;
      ASSERT_GT(best, 0.0) << "trial " << trial << ": density " << kept << " after erosion " << erosion
                           << " at h " << seen << " in [" << h0 << ", " << h1 << "], every texel's bound " << best;
    }
  }
  EXPECT_GT(positive, 1000) << "enough mixes keep density for the check to mean something";
}

// Cells that do not divide a tiling volume leave a partial last cell. The occupancy lookups wrap
// at the tile's period in voxels (medium.glsl static_cell), not every n cells, and the distance
// field counts a route across the seam as one cell shorter (occupancy_distance): layer mode, where
// the texture repeats across the sky, skips exactly with both schemes, and the field still skips.
// (Before, the thesis scheme read the wrong cells beyond the first repeat and changed the image,
// and the field was capped at 1, so distance skipping never jumped.)
TEST(Skipping, PartialCellsOnATilingVolumeSkipExactly) {
  const int cell = 5;
  for (const char* kind : {"noise", "blob"}) {
    cloudgen::Volume input = testutil::synthetic(kind);
    input.tiles_xz = true;  // the blob repeated across the sky: much empty space between the repeats
    const PreparedVolume vol = prepare_volume(input, cell, 2);
    ASSERT_TRUE(vol.tiles);
    ASSERT_NE(vol.dims[0] % cell, 0) << "a partial last cell";
    RenderSettings s = with({"render.mode=layer", "render.steps=64"});
    s.occupancy_cell = cell;
    const Camera cam = default_camera(vol, s, 60, kAspect);
    const Sun sun = default_sun(cam);
    for (bool on_gl : {true, false}) {
      const std::string side = std::string(kind) + (on_gl ? " GL" : " CPU");
      RenderSettings none = s, thesis = s, dist = s;
      none.skipping = Skipping::None;
      thesis.skipping = Skipping::Thesis;
      dist.skipping = Skipping::Distance;
      const FrameSetup fd = make_frame(vol, dist, cam, sun, kW, kH);
      ASSERT_EQ(fd.params.skip_distance, 1.0) << side;
      const FrameImages a = render(on_gl, vol, make_frame(vol, none, cam, sun, kW, kH));
      EXPECT_GT(image_stats(a.display).stddev, 0.01) << side << ": a picture to compare";
      // GL's thesis program differs from the plain one by float rounding in layer mode (up to 1e-6
      // here, as ViewerLayer.GlMatchesCpuAndSkippingIsImageNeutral allows); reading the wrong cells
      // changed the tiled blob by 0.99 (whole repeats missing).
      const double thesis_diff = max_abs_diff(a.linear, render(on_gl, vol, make_frame(vol, thesis, cam, sun, kW, kH)).linear);
      std::cout << side << ": thesis scheme against no skipping, max |diff| " << thesis_diff << "\n";
      EXPECT_LE(thesis_diff, on_gl ? 1e-5 : 0.0) << side << " thesis";
      EXPECT_EQ(max_abs_diff(a.linear, render(on_gl, vol, fd).linear), 0.0) << side << " distance";
      const double t_none = loop_trips(on_gl, vol, none, cam, kW, kH), t_dist = loop_trips(on_gl, vol, dist, cam, kW, kH);
      std::cout << side << ": loop trips without skipping / with the field " << t_none << " / " << t_dist << "\n";
      EXPECT_LT(t_dist, 0.8 * t_none) << side << ": the field skips";
    }
  }
}

// The thesis scheme's large step spans the padding's clearance (frame.cpp make_frame): from any
// point of an unoccupied cell, no density lies within one large step along every axis at once
// (L-infinity), for paddings 1 to 3, on a tiling volume whose cells of 4 divide it and on one that
// leaves a 1-voxel cell at the seam, with density right at the seam. There P cells across the wrap
// span (P - 1) x 4 + 1 voxels, not P x 4: the clearance that ignores the partial cell must fail the
// same check (the check can fail; at padding 1 that was the step before, one cell less half a voxel).
TEST(Skipping, ThesisLargeStepStaysWithinThePaddingsClearance) {
  const int cell = 4;
  for (uint32_t side : {56u, 57u})
  for (int padding : {1, 2, 3}) {
    cloudgen::Volume input;
    input.dims = {side, 12, side};
    input.voxel_size = 10;
    input.origin = {-200, 400, -200};
    input.tiles_xz = true;
    input.density.assign(input.voxel_count(), 0.f);
    for (uint32_t a = 10; a < 30; ++a)
      for (uint32_t y = 3; y < 9; ++y) {
        input.density[input.index(0, y, a)] = 1.f;  // the planes x = 0 and z = 0, at the seam
        input.density[input.index(a, y, 0)] = 1.f;
      }
    const PreparedVolume vol = prepare_volume(input, cell, padding);
    RenderSettings s = with({"render.skipping=thesis", "render.steps=256", "render.erosion=0"});
    s.occupancy_cell = cell;
    s.occupancy_padding = padding;
    const Camera cam = default_camera(vol, s, 60, 16.0 / 9);
    const FrameSetup f = make_frame(vol, s, cam, default_sun(cam), kW, kH);
    const std::string at = "side " + std::to_string(side) + " padding " + std::to_string(padding);
    const double dt = f.params.step_m, large = f.params.large_step_count * dt;
    const double voxel = vol.voxel_size;
    const bool partial = side % cell != 0;
    EXPECT_NEAR(large, std::floor(0.999 * ((padding - (partial ? 0.75 : 0.0)) * cell - 0.5) * voxel / dt) * dt, 1e-9)
        << at << ": the step the padding allows";
    // Few steps: at padding 1 the seam's clearance (half a voxel) is under one small step (1.8
    // voxels), and the thesis scheme must stop rather than skip a sample it cannot prove empty.
    RenderSettings few = s;
    few.steps = 32;
    EXPECT_EQ(make_frame(vol, few, cam, default_sun(cam), kW, kH).params.occupancy_skip,
              partial && padding == 1 ? 0.0 : 1.0) << at << " at 32 steps";
    const double naive = std::floor(0.999 * (padding * cell - 0.5) * voxel / dt) * dt;
    const glm::dvec3 lo = f.params.volume_min_m, hi = lo + f.params.volume_size_m;
    auto unoccupied = [&](glm::dvec3 p) {
      glm::ivec3 c(glm::floor((p - lo) / voxel / double(cell)));
      c = glm::clamp(c, glm::ivec3(0), glm::ivec3(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]) - 1);
      return vol.occ[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x] == 0;
    };
    uint32_t state = 7;
    auto next = [&] { return ((state = state * 1664525u + 1013904223u) >> 8) / double(1u << 24); };
    int tried = 0, naive_hits = 0;
    for (int i = 0; i < 20000; ++i) {
      const glm::dvec3 p = lo + (hi - lo) * glm::dvec3(next(), next(), next());
      if (!unoccupied(p)) continue;
      ++tried;
      ASSERT_EQ(reference_density(vol, f, p), 0.0) << at;
      for (int k = 0; k < 26; ++k) {  // the corners, edges and faces of the L-infinity ball
        const int j = k < 13 ? k : k + 1;  // 13 is the centre
        const glm::dvec3 d(j % 3 - 1.0, (j / 3) % 3 - 1.0, j / 9 - 1.0);
        auto inside = [&](glm::dvec3 q) { return glm::clamp(q, lo, hi - 1e-6 * voxel); };
        ASSERT_EQ(reference_density(vol, f, inside(p + d * large)), 0.0)
            << at << ": density one large step from the unoccupied point (" << p.x << ", " << p.y << ", " << p.z
            << ") m, toward (" << d.x << ", " << d.y << ", " << d.z << ")";
        if (reference_density(vol, f, inside(p + d * naive)) > 0) ++naive_hits;
      }
    }
    EXPECT_GT(tried, 2000) << at << ": unoccupied space to test";
    std::cout << at << ": large step " << large / voxel << " voxels; the step blind to the partial cell ("
              << naive / voxel << ") reaches density from " << naive_hits << " points\n";
    if (partial) {
      EXPECT_GT(naive_hits, 0) << at << ": the check can fail";
    }
  }
}

// Moving layers jump by the still field, read at the static point seen and shortened by the
// motion's stretch (lighting.glsl empty_radius_of, frame.cpp apply_motion): the same image as no
// skipping, GL and CPU, at two times with strong shear and up flow, with fewer loop trips than the
// thesis scheme (which the stretch here shortens below one small step, so it is off). Jumps not
// shortened (stretch 1) change the image at 300 s (by 1.65 on the blob, 0.08 on the noise): the
// check can fail.
TEST(Skipping, MovingLayersJumpByTheStillFieldExactly) {
  const std::vector<std::pair<const char*, double>> cases = {{"blob", 40.0}, {"blob", 300.0}, {"noise", 300.0}};
  for (const auto& [kind, time] : cases) {
    cloudgen::Volume input = testutil::synthetic(kind);
    input.tiles_xz = true;  // the blob repeated across the sky
    {
      RenderSettings s = with({"render.mode=layer", "render.steps=64", "motion.wind_speed=8", "motion.wind_shear=3",
                               "motion.flow_up=300"});
      s.time = time;
      PreparedVolume vol = prepare_volume(input, 4, 2, &s);  // the field fitted to the motion
      const Camera cam = default_camera(vol, s, 60, kAspect);
      const Sun sun = default_sun(cam);
      RenderSettings none = s, thesis = s, dist = s;
      none.skipping = Skipping::None;
      thesis.skipping = Skipping::Thesis;
      dist.skipping = Skipping::Distance;
      const FrameSetup fd = make_frame(vol, dist, cam, sun, kW, kH);
      const std::string at = std::string(kind) + " t " + std::to_string(int(time));
      ASSERT_EQ(fd.params.motion_on, 1.0) << at;
      ASSERT_EQ(fd.params.skip_distance, 1.0) << at;
      ASSERT_GT(fd.params.motion_stretch, 1.5) << at << ": a stretch that matters";
      for (bool on_gl : {true, false}) {
        const std::string what = at + (on_gl ? " GL" : " CPU");
        const FrameImages a = render(on_gl, vol, make_frame(vol, none, cam, sun, kW, kH));
        EXPECT_GT(image_stats(a.display).stddev, 0.01) << what << ": a picture to compare";
        EXPECT_EQ(max_abs_diff(a.linear, render(on_gl, vol, fd).linear), 0.0) << what;
        const double tn = loop_trips(on_gl, vol, none, cam, kW, kH), tt = loop_trips(on_gl, vol, thesis, cam, kW, kH),
                     td = loop_trips(on_gl, vol, dist, cam, kW, kH);
        std::cout << what << ": stretch " << fd.params.motion_stretch << ", loop trips none / thesis / distance " << tn
                  << " / " << tt << " / " << td << "\n";
        EXPECT_LT(td, tt) << what << ": the field jumps farther than the thesis's large step";
        FrameSetup unshortened = fd;
        unshortened.params.motion_stretch = 1.0;
        const double lie = max_abs_diff(a.linear, render(on_gl, vol, unshortened).linear);
        std::cout << what << ": jumps not shortened change the image by " << lie << "\n";
        if (time > 100) {
          EXPECT_GT(lie, 0.05) << what << ": the check can fail";
        }
      }
    }
  }
}

// The eroded distance field (fit_distance_field, docs/viewer-speed.md): cells whose base the
// erosion removes are empty too, so distance skipping jumps farther, and the image stays the plain
// march's bit for bit: still and moving (the up flow's height slack), box and layer placement
// (moving layers jump by it too), GL and CPU. A field built for a stronger erosion than the frame's changes the image (the rule is
// what keeps it exact), and make_frame does not trust a field its settings are not covered by.
TEST(Skipping, ErodedFieldSkipsExactly) {
  struct ErodedCase {
    const char* name;
    const char* input;
    std::vector<const char*> sets;
    double time;
  };
  const std::vector<ErodedCase> cases = {
      {"blob", "blob", {}, 0},
      {"blob moving", "blob", {"motion.wind_speed=6", "motion.wind_shear=3", "motion.flow_up=200"}, 40},
      {"layer", "noise", {"render.mode=layer", "render.steps=64"}, 0},
  };
  for (const ErodedCase& c : cases) {
    RenderSettings s = with({"render.steps=128"});
    for (const char* a : c.sets) apply_setting(s, a);
    s.time = c.time;
    const PreparedVolume base = prepare_volume(testutil::synthetic(c.input), 4, 2);
    ASSERT_EQ(base.dist_rule.erosion, 0.0) << c.name << ": prepare_volume builds the base field";
    PreparedVolume vol = base;
    ASSERT_TRUE(fit_distance_field(vol, s)) << c.name;
    EXPECT_EQ(vol.dist_rule.erosion, s.erosion) << c.name;
    EXPECT_EQ(vol.dist_rule.height_slack > 0, c.time != 0) << c.name;
    EXPECT_FALSE(fit_distance_field(vol, s)) << c.name << ": fitted once";
    {  // prepare_volume builds the same field at once, and a rebuild of the grid keeps its rule
      PreparedVolume fitted = prepare_volume(testutil::synthetic(c.input), 4, 2, &s);
      EXPECT_TRUE(fitted.dist_rule == vol.dist_rule) << c.name;
      EXPECT_TRUE(fitted.dist == vol.dist) << c.name;
      build_occupancy(fitted, 4, 2);
      EXPECT_TRUE(fitted.dist_rule == vol.dist_rule) << c.name << ": build_occupancy keeps the eroded field";
      EXPECT_TRUE(fitted.dist == vol.dist) << c.name;
    }
    RenderSettings off = s;
    off.eroded_field = false;
    EXPECT_EQ(field_rule(vol, off).erosion, 0.0) << c.name << ": render.eroded_field=false asks for the base field";
    size_t held_base = 0, held = 0;
    for (size_t i = 0; i < vol.dist.size(); ++i) held_base += base.dist[i] == 0, held += vol.dist[i] == 0;
    std::cout << c.name << ": cells holding density " << held_base << " (base) / " << held << " (eroded)\n";
    EXPECT_LT(double(held), 0.95 * double(held_base)) << c.name << ": the erosion empties cells";
    const Camera cam = default_camera(vol, s, 60, kAspect);
    const Sun sun = default_sun(cam);
    for (bool on_gl : {true, false}) {
      const std::string what = std::string(c.name) + (on_gl ? " GL" : " CPU");
      RenderSettings none = s, dist = s;
      none.skipping = Skipping::None;
      dist.skipping = Skipping::Distance;
      const FrameSetup fd = make_frame(vol, dist, cam, sun, kW, kH);
      ASSERT_EQ(fd.params.skip_distance, 1.0) << what;
      FrameImages a = render(on_gl, vol, make_frame(vol, none, cam, sun, kW, kH));
      FrameImages b = render(on_gl, vol, fd);
      EXPECT_GT(image_stats(a.display).stddev, 0.01) << what << ": a picture to compare";
      EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << what;
      EXPECT_EQ(max_abs_diff(a.display, b.display), 0.0) << what;
      const double t_base = loop_trips(on_gl, base, dist, cam, kW, kH), t_eroded = loop_trips(on_gl, vol, dist, cam, kW, kH);
      std::cout << what << ": loop trips with the base / eroded field " << t_base << " / " << t_eroded << "\n";
      EXPECT_LT(t_eroded, 0.97 * t_base) << what;
      if (c.time == 0) {
        // Sensitivity: a field built for erosion 0.8 and trusted at 0.35 skips density. The image
        // checks above ask for max |diff| 0; this asks the lie to show well above rounding (blob:
        // 0.0093 since the march reads the field at the sample point, 0.3 in the layer).
        PreparedVolume lie = vol;
        FieldRule strong = vol.dist_rule;
        strong.erosion = 0.8;
        build_distance_field(lie, strong);
        lie.dist_rule = FieldRule{};
        const double lie_diff = max_abs_diff(a.linear, render(on_gl, lie, make_frame(lie, dist, cam, sun, kW, kH)).linear);
        std::cout << what << ": the lying field changes the image by " << lie_diff << "\n";
        EXPECT_GT(lie_diff, 1e-3)
            << what << ": the check can fail";
      }
    }
    // Less erosion than the field assumed, or curl moving the detail: not covered, so the frame skips
    // by the thesis scheme, and fit_distance_field rebuilds.
    RenderSettings weaker = s, curl = s;
    weaker.erosion = 0.2;
    curl.motion.curl_amplitude = 100;
    EXPECT_EQ(make_frame(vol, weaker, cam, sun, 16, 9).params.skip_distance, 0.0) << c.name;
    EXPECT_EQ(make_frame(vol, curl, cam, sun, 16, 9).params.skip_distance, 0.0) << c.name;
    RenderSettings stronger = s;
    stronger.erosion = 0.5;
    EXPECT_EQ(make_frame(vol, stronger, cam, sun, 16, 9).params.skip_distance, 1.0) << c.name << ": still exact";
    PreparedVolume refit = vol;
    EXPECT_TRUE(fit_distance_field(refit, weaker)) << c.name;
    EXPECT_EQ(make_frame(refit, weaker, cam, sun, 16, 9).params.skip_distance, 1.0) << c.name;
    EXPECT_TRUE(fit_distance_field(refit, curl)) << c.name;
    EXPECT_EQ(refit.dist_rule.erosion, 0.0) << c.name << ": curl: the base field";
  }
}

// common.glsl's wrap_index, compiled here as the CPU reference compiles it: it wraps without an
// integer division (the march wraps three cells per trip, and SIMD hardware divides integers one
// lane at a time), so it must still be exactly i mod n. (The GL side, in float, is checked by the
// tests that compare GL with the CPU reference on tiling volumes with skipping on, whose cells it
// wraps: DistanceSkippingDoesNotChangeTheImage, ErodedFieldSkipsExactly.)
#include "../viewer/src/cpu/glsl_cpp.h"  // last: defines IN/OUT/INOUT
namespace glsl_common {
using namespace glm;
struct Double {
  CV_GLSL_DOUBLE_TYPES;
#include "../viewer/shaders/common.glsl"
};
}  // namespace glsl_common

TEST(Skipping, WrapIndexIsExactWithoutIntegerDivision) {
  glsl_common::Double d{};
  long checked = 0;
  for (int n : {1, 2, 3, 5, 7, 16, 31, 32, 33, 43, 64, 100, 127, 128, 255, 256, 1000, 2048, 4099}) {
    for (int i = -200000; i <= 200000; ++i) {
      const int want = ((i % n) + n) % n;
      const int got = d.wrap_index(i, n);
      if (got != want) {
        ADD_FAILURE() << "wrap_index(" << i << ", " << n << ") = " << got << ", want " << want;
        return;
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 19L * 400001L);
}

// render.occupancy_cell is doubled for large volumes (opening and refitting the distance field take
// time in proportion to the cells): below 4 voxels while the grid would exceed 8 M cells, at any
// size while it would exceed 32 M; never coarser than needed, never finer than asked.
TEST(Skipping, OccupancyCellGrowsWithTheVolumeOnly) {
  auto cells = [](int c, uint64_t nx, uint64_t ny, uint64_t nz) {
    const uint64_t u = uint64_t(c);
    return ((nx + u - 1) / u) * ((ny + u - 1) / u) * ((nz + u - 1) / u);
  };
  EXPECT_EQ(occupancy_cell_for(2, 128, 128, 128), 2);     // the thesis volume
  EXPECT_EQ(occupancy_cell_for(2, 512, 128, 512), 2);     // cumulus-field 512: 4.2 M cells
  EXPECT_EQ(occupancy_cell_for(2, 1024, 146, 1024), 4);   // cumulus-field 1024: 19 M at 2
  EXPECT_EQ(occupancy_cell_for(2, 2048, 292, 2048), 4);   // cumulus-field 2048: 19 M at 4
  EXPECT_EQ(occupancy_cell_for(8, 128, 128, 128), 8);     // never finer than asked
  uint32_t h = 7;
  for (int trial = 0; trial < 2000; ++trial) {
    const uint64_t nx = 1 + lcg(h) % 8192, ny = 1 + lcg(h) % 1024, nz = 1 + lcg(h) % 8192;
    const int asked = 2 + int(lcg(h) % 15);
    const int c = occupancy_cell_for(asked, nx, ny, nz);
    ASSERT_GE(c, asked);
    ASSERT_LE(cells(c, nx, ny, nz), kMaxOccupancyCells) << nx << "x" << ny << "x" << nz;
    if (c < 4) {
      ASSERT_LE(cells(c, nx, ny, nz), kMaxFineOccupancyCells);
    }
    if (c > asked) {  // doubled only because the half was too many cells
      const uint64_t half = cells(c / 2, nx, ny, nz);
      ASSERT_TRUE(half > kMaxOccupancyCells || (c / 2 < 4 && half > kMaxFineOccupancyCells))
          << nx << "x" << ny << "x" << nz << " asked " << asked << " got " << c;
    }
  }
}
