// Shape sources (cloudgen/shape.h): each source puts cloud where its analytic interior is, the
// smooth union fills the neck between sources, skipping stays exact and thread counts give the same
// bytes, presets without sources keep their bytes, and bad input names the field and what is allowed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "cloudgen/generate.h"
#include "cloudgen/preset.h"
#include "cloudgen/shape.h"
#include "test_util.h"

using namespace cloudgen;

namespace {

using testutil::run_cli;
using testutil::same_bytes;
using testutil::TempDir;

using Inside = std::function<bool(double x, double y, double z)>;

// 64^3 voxels of 10 m from the origin: voxel i is centred at (i + 0.5) * 10 m.
constexpr int kN = 64;
constexpr double kVs = 10;

/// A preset of kN^3 voxels with `shape` as its shape section; `neutral` makes the noise R exactly
/// 1 (remap [-1, -0.5] sends every value to 1) and the threshold 0.5, so density > 0 exactly
/// where s > 0.5, i.e. inside the sources (d < 0).
Preset shaped(const std::string& shape, bool neutral, const std::string& extra = "") {
  std::string j = R"({"resolution": [64, 64, 64], "voxel_size": 10, "tiling": false, "shape": )" + shape;
  if (neutral) j += R"(, "threshold": 0.5, "channels": {"r": {"remap": [-1, -0.5]}})";
  return parse_preset(j + extra + "}", "shaped.json");
}

double centre(int i) { return (i + 0.5) * kVs; }

/// Intersection over union of density > 0 and the analytic interior, over the voxel centres.
double iou(const Volume& v, const Inside& inside) {
  size_t inter = 0, uni = 0;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const bool a = v.density[v.index(x, y, z)] > 0, b = inside(centre(x), centre(y), centre(z));
        inter += a && b, uni += a || b;
      }
  return uni ? double(inter) / uni : 0.0;
}

/// Voxels with density > 0 where `near` (the interior grown by falloff / 2) is false.
size_t outside_count(const Volume& v, const Inside& near) {
  size_t n = 0;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) n += v.density[v.index(x, y, z)] > 0 && !near(centre(x), centre(y), centre(z));
  return n;
}

double seg_dist(double x, double y, double z, const double a[3], const double b[3]) {
  const double ba[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, pa[3] = {x - a[0], y - a[1], z - a[2]};
  double h = (pa[0] * ba[0] + pa[1] * ba[1] + pa[2] * ba[2]) / (ba[0] * ba[0] + ba[1] * ba[1] + ba[2] * ba[2]);
  h = std::clamp(h, 0.0, 1.0);
  return std::hypot(pa[0] - h * ba[0], pa[1] - h * ba[1], pa[2] - h * ba[2]);
}

struct SourceCase {
  const char* name;
  std::string shape;
  Inside inside;  ///< the analytic interior, written out here independently of shape.cpp
  Inside near;    ///< the interior grown by at least falloff / 2 = 50 m
};

std::vector<SourceCase> source_cases() {
  // Ellipsoid radii (220, 110, 140) turned 30 degrees about +y (right-handed: +x towards -z), so a
  // world offset (dx, dz) is (c dx - s dz, s dx + c dz) in its own axes.
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  auto ell = [=](double grow) {
    return [=](double x, double y, double z) {
      const double dx = x - 320, dy = y - 300, dz = z - 330, u = (c * dx - s * dz) / 220, w = (s * dx + c * dz) / 140;
      return std::sqrt(u * u + (dy / 110) * (dy / 110) + w * w) < 1 + grow / 110;
    };
  };
  // The capsule turned 90 degrees about +y about its middle (320, 320, 320): a - m = (-170, -70, 0)
  // becomes (0, -70, 170).
  static const double ca[3] = {320, 250, 490}, cb[3] = {320, 390, 150};
  return {
      {"ellipsoid",
       R"({"falloff": 100, "sources": [{"kind": "ellipsoid", "center": [320, 300, 330], "radii": [220, 110, 140], "rotate": [0, 30, 0]}]})",
       ell(0), ell(50)},
      {"sphere", R"({"falloff": 100, "sources": [{"kind": "sphere", "center": [300, 320, 340], "radius": 170, "translate": [20, 0, -20]}]})",
       [](double x, double y, double z) { return std::hypot(x - 320, y - 320, z - 320) < 170; },
       [](double x, double y, double z) { return std::hypot(x - 320, y - 320, z - 320) < 220; }},
      {"capsule",
       R"({"falloff": 100, "sources": [{"kind": "capsule", "a": [150, 250, 320], "b": [490, 390, 320], "radius": 90, "rotate": [0, 90, 0]}]})",
       [](double x, double y, double z) { return seg_dist(x, y, z, ca, cb) < 90; },
       [](double x, double y, double z) { return seg_dist(x, y, z, ca, cb) < 140; }},
  };
}

std::string error_of(const std::string& json, std::vector<std::string> sets = {}) {
  try {
    parse_preset(json, "bad.json", sets);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// With the noise neutralised the cloud is the set of voxel centres inside the source (d < 0 is
// s > 0.5): what is left of the IoU's gap is rounding at centres on the surface. With the noise
// eroding (the default R, threshold 0.3) the cloud still lies within falloff / 2 of the source
// (R <= 1), and mostly fills it.
TEST(Shape, EachSourcePutsCloudInsideItself) {
  for (const SourceCase& sc : source_cases()) {
    SCOPED_TRACE(sc.name);
    const Volume neutral = generate(shaped(sc.shape, true));
    const double iou_neutral = iou(neutral, sc.inside);
    const Volume eroded = generate(shaped(sc.shape, false));
    const double iou_eroded = iou(eroded, sc.inside);
    std::printf("  %s: IoU %.4f with the noise neutralised, %.4f with it eroding\n", sc.name, iou_neutral, iou_eroded);
    EXPECT_GE(iou_neutral, 0.99);
    EXPECT_GE(iou_eroded, 0.75);
    EXPECT_EQ(outside_count(neutral, sc.near), 0u);
    EXPECT_EQ(outside_count(eroded, sc.near), 0u);
  }
}

// Two ellipsoids that overlap a little: with blend 0 the cloud is their union exactly; with blend
// 150 m it still holds both and fills the neck between them beyond either surface.
TEST(Shape, SmoothUnionFillsTheNeckAndHoldsBoth) {
  auto ell = [](double cx) {
    return [=](double x, double y, double z) {
      return std::sqrt(std::pow((x - cx) / 120, 2) + std::pow((y - 320) / 80, 2) + std::pow((z - 320) / 80, 2)) < 1;
    };
  };
  const Inside e1 = ell(220), e2 = ell(420);
  const Inside both = [&](double x, double y, double z) { return e1(x, y, z) || e2(x, y, z); };
  auto shape = [](int blend) {
    return R"({"falloff": 100, "blend": )" + std::to_string(blend) +
           R"(, "sources": [{"kind": "ellipsoid", "center": [220, 320, 320], "radii": [120, 80, 80]},
                            {"kind": "ellipsoid", "center": [420, 320, 320], "radii": [120, 80, 80]}]})";
  };
  const Volume hard = generate(shaped(shape(0), true)), soft = generate(shaped(shape(150), true));
  EXPECT_GE(iou(hard, both), 0.99);
  size_t holes = 0, neck_hard = 0, neck_soft = 0, extra_soft = 0;
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const bool in = both(centre(x), centre(y), centre(z));
        const size_t i = soft.index(x, y, z);
        holes += in && !(soft.density[i] > 0);
        const bool neck = centre(x) > 290 && centre(x) < 350;  // around the plane x = 320 where they meet
        neck_hard += neck && hard.density[i] > 0;
        neck_soft += neck && soft.density[i] > 0;
        extra_soft += neck && !in && soft.density[i] > 0 && hard.density[i] == 0;
      }
  std::printf("  neck voxels: %zu hard, %zu blended (%zu beyond both surfaces)\n", neck_hard, neck_soft, extra_soft);
  EXPECT_EQ(holes, 0u) << "the smooth union must contain both ellipsoids";
  EXPECT_GT(neck_soft, neck_hard + neck_hard / 4) << "blend 150 m must thicken the neck";
  EXPECT_GT(extra_soft, 0u);
  // A point of the neck outside both ellipsoids: cloud with the blend, none without.
  const size_t p = hard.index(32, 37, 31);  // (325, 375, 315) m
  EXPECT_FALSE(both(325, 375, 315));
  EXPECT_EQ(hard.density[p], 0.0f);
  EXPECT_GT(soft.density[p], 0.0f);
}

namespace {

// Three blended sources and a detail channel, in a tiling volume (the shape fades out inside the
// tile, so the detail's one-voxel halo wraps) or not.
Preset three_sources(bool tiling) {
  return parse_preset(std::string(R"({"resolution": [96, 64, 80], "voxel_size": 10, "tiling": )") +
                          (tiling ? "true" : "false") + R"(,
      "channels": {"g": {"enabled": true}},
      "shape": {"blend": 120, "falloff": 150, "sources": [
        {"kind": "ellipsoid", "center": [420, 260, 400], "radii": [220, 120, 150], "rotate": [10, 25, -5]},
        {"kind": "sphere", "center": [300, 330, 380], "radius": 110, "scale": [1.3, 1, 0.8]},
        {"kind": "capsule", "a": [520, 220, 300], "b": [640, 300, 480], "radius": 70}]}})",
                      "three.json");
}

}  // namespace

// Skipping never changes a byte, and it skips (without evaluating noise) at least every brick
// whose voxel centres all lie beyond falloff / 2 of the sources.
TEST(Shape, SkippingIsExact) {
  for (bool tiling : {false, true}) {
    SCOPED_TRACE(tiling ? "tiling" : "not tiling");
    const Preset p = three_sources(tiling);
    GenerateOptions on, off;
    off.skip_empty = false;
    GenerateStats s_on, s_off;
    const Volume a = generate(p, on, &s_on), b = generate(p, off, &s_off);
    EXPECT_TRUE(same_bytes(a.density, b.density));
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bytes(a.detail[c], b.detail[c])) << "channel " << c;
    EXPECT_GT(s_on.active_voxels, 0u);
    EXPECT_GT(s_on.bricks_skipped, s_on.bricks / 3);
    EXPECT_EQ(s_off.bricks_skipped, 0u);
  }
  // One sphere of 120 m in a 960 m box: every brick with no voxel centre within 120 + 50 m of its
  // centre is skipped.
  const Preset p = parse_preset(R"({"resolution": [96, 96, 96], "voxel_size": 10, "tiling": false,
      "shape": {"falloff": 100, "sources": [{"kind": "sphere", "center": [480, 480, 480], "radius": 120}]}})",
                                "one.json");
  size_t far = 0;
  for (int bz = 0; bz < 6; ++bz)
    for (int by = 0; by < 6; ++by)
      for (int bx = 0; bx < 6; ++bx) {
        double d2 = 0;  // squared distance from the sphere's centre to the brick's nearest voxel centre
        for (int b : {bx, by, bz}) {
          const double lo = (b * 16 + 0.5) * 10, hi = (b * 16 + 15.5) * 10, c = std::clamp(480.0, lo, hi);
          d2 += (c - 480) * (c - 480);
        }
        far += std::sqrt(d2) > 170;
      }
  GenerateStats st;
  GenerateOptions no_detail;
  const Volume v = generate(p, no_detail, &st);
  std::printf("  one sphere: %zu of %zu bricks skipped, %zu beyond its reach\n", st.bricks_skipped, st.bricks, far);
  EXPECT_GT(far, 150u);
  EXPECT_GE(st.bricks_skipped, far);
  EXPECT_GT(st.active_voxels, 0u);
}

TEST(Shape, SameBytesAtAnyThreadCountAndRegion) {
  const Preset p = three_sources(true);
  GenerateOptions one, two;
  one.threads = 1, two.threads = 2;
  const Volume a = generate(p, one), b = generate(p, two);
  EXPECT_TRUE(same_bytes(a.density, b.density));
  EXPECT_TRUE(same_bytes(a.detail[0], b.detail[0]));
  GenerateOptions r;
  r.region_origin = {7, 11, 19};
  r.region_extent = {53, 29, 37};
  const Volume part = generate(p, r);
  for (uint32_t z = 0; z < 37; ++z)
    for (uint32_t y = 0; y < 29; ++y)
      for (uint32_t x = 0; x < 53; ++x) {
        ASSERT_EQ(part.density[part.index(x, y, z)], a.density[a.index(x + 7, y + 11, z + 19)]);
        ASSERT_EQ(part.detail[0][part.index(x, y, z)], a.detail[0][a.index(x + 7, y + 11, z + 19)]);
      }
}

// A shape section without sources changes neither the bytes nor the preset hash (the golden
// checksums of the shipped presets stay); sources do change the hash.
TEST(Shape, NoSourcesLeaveBytesAndHashAsBefore) {
  const Preset plain = load_preset(testutil::kPresets + "tiny.json");
  const Preset empty = load_preset(testutil::kPresets + "tiny.json", {"shape.blend=40", "shape.falloff=80"});
  EXPECT_TRUE(same_bytes(generate(plain).density, generate(empty).density));
  EXPECT_EQ(preset_hash(plain), preset_hash(empty));
  const Preset one = load_preset(testutil::kPresets + "tiny.json",
                                 {"tiling=false", R"(shape.sources=[{"kind": "sphere", "center": [100, 100, 100], "radius": 50}])"});
  EXPECT_NE(preset_hash(plain), preset_hash(one));
  const Preset two = load_preset(testutil::kPresets + "tiny.json",
                                 {"tiling=false", R"(shape.sources=[{"kind": "sphere", "center": [100, 100, 100], "radius": 51}])"});
  EXPECT_NE(preset_hash(one), preset_hash(two));
}

TEST(Shape, SetOverridesReachEveryKey) {
  const Preset p = parse_preset(R"({"tiling": false, "shape": {"sources": [{"kind": "sphere", "center": [1, 2, 3], "radius": 5}]}})",
                                "x.json", {"shape.blend=75", "shape.sources.0.radius=40", "shape.sources.0.rotate=[0, 90, 0]"});
  EXPECT_EQ(p.shape.blend, 75);
  EXPECT_EQ(*p.shape.sources[0].radius, 40);
  EXPECT_EQ(p.shape.sources[0].rotate[1], 90);
  EXPECT_EQ(p.shape.falloff, 100) << "the table's default";
}

TEST(Shape, BadInputNamesTheFieldAndWhatIsAllowed) {
  struct Case {
    std::string sources, expect;
  };
  const std::vector<Case> cases = {
      {R"([{"kind": "sphere", "center": [0, 0, 0], "radius": -5}])",
       "/shape/sources/0/radius: -5 is out of range; allowed: number in [0.001, 1e+09]"},
      {R"([{"kind": "sphere", "center": [0, 0, 0], "radius": 0}])", "/shape/sources/0/radius: 0 is out of range"},
      {R"([{"kind": "ellipsoid", "center": [0, 0, 0], "radii": [100, 0, 100]}])",
       "/shape/sources/0/radii/1: 0 is out of range; allowed: number in [0.001, 1e+09]"},
      {R"([{"kind": "cube", "center": [0, 0, 0]}])",
       "/shape/sources/0/kind: \"cube\" is not allowed; expected one of: ellipsoid | sphere | capsule"},
      {R"([{"center": [0, 0, 0], "radius": 4}])", "/shape/sources/0/kind: missing; expected one of: ellipsoid | sphere | capsule"},
      {R"([{"kind": "sphere", "center": [0, 0, 0]}])", "/shape/sources/0: a sphere needs \"radius\""},
      {R"([{"kind": "capsule", "a": [0, 0, 0], "radius": 3}])", "/shape/sources/0: a capsule needs \"b\""},
      {R"([{"kind": "sphere", "center": [0, 0, 0], "radius": 3, "radii": [1, 2, 3]}])",
       "/shape/sources/0/radii: is not a key of a sphere"},
      {R"([{"kind": "capsule", "a": [0, 0, 0], "b": [1, 0, 0], "radius": 3, "scale": [1, 2, 1]}])",
       "/shape/sources/0/scale: a capsule takes a uniform scale"},
      {R"([{"kind": "sphere", "center": [0, 0, 0], "radious": 3}])",
       "/shape/sources/0/radious: unknown key (did you mean \"radius\"?)"},
      {R"([{"kind": "sphere", "center": [0, "x", 0], "radius": 3}])", "/shape/sources/0/center/1: \"x\" has the wrong type"},
      {R"([{"kind": "sphere", "center": [0, 0, 0], "radius": 3, "rotate": [0, 400, 0]}])",
       "/shape/sources/0/rotate/1: 400 is out of range; allowed: number in [-360, 360]"},
      {R"({"kind": "sphere"})", "/shape/sources: {\"kind\":\"sphere\"} has the wrong type; expected a list"},
  };
  for (const Case& c : cases) {
    const std::string e = error_of(R"({"tiling": false, "shape": {"sources": )" + c.sources + "}}");
    EXPECT_NE(e.find("bad.json: " + c.expect), std::string::npos) << "for " << c.sources << "\n got: " << e << "\n want: " << c.expect;
  }
  std::string many = "[";
  for (int i = 0; i < 65; ++i) many += std::string(i ? ", " : "") + R"({"kind": "sphere", "center": [0, 0, 0], "radius": 1})";
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"sources": )" + many + "]}}").find("/shape/sources: 65 sources; at most 64"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"shape": {"falloff": 0}})").find("/shape/falloff: 0 is out of range; allowed: number in [0.001, 1e+09]"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"shape": {"blend": -1}})").find("/shape/blend: -1 is out of range"), std::string::npos);
  EXPECT_NE(error_of("{}", {"shape.blend=nan"}).find("/shape/blend: \"nan\" has the wrong type; expected a number"),
            std::string::npos);
  // Shapes do not wrap: in a tiling volume the shape must fade out before the x and z faces.
  const std::string e = error_of(R"({"resolution": [64, 32, 64], "voxel_size": 10,
      "shape": {"falloff": 100, "sources": [{"kind": "sphere", "center": [600, 100, 320], "radius": 30}]}})");
  EXPECT_NE(e.find("/shape/sources: with /tiling true the shape must be 0 on the voxels of the x and z faces"), std::string::npos) << e;
  EXPECT_NE(e.find("(635, "), std::string::npos) << "names the voxel on the x face: " << e;
  EXPECT_EQ(error_of(R"({"resolution": [64, 32, 64], "voxel_size": 10, "tiling": false,
      "shape": {"falloff": 100, "sources": [{"kind": "sphere", "center": [600, 100, 320], "radius": 30}]}})"),
            "");
}

TEST(Shape, CliValidatesAndGeneratesShapedPresets) {
  TempDir dir;
  std::string out;
  testutil::write_text(dir / "bad.json", R"({"tiling": false, "shape": {"sources": [{"kind": "sphere", "center": [0, 0, 0], "radius": -1}]}})");
  EXPECT_EQ(run_cli("validate " + (dir / "bad.json"), &out), 1) << out;
  EXPECT_NE(out.find("/shape/sources/0/radius: -1 is out of range"), std::string::npos) << out;
  testutil::write_text(dir / "ok.json", R"({"resolution": [32, 32, 32], "voxel_size": 10, "tiling": false,
      "shape": {"sources": [{"kind": "sphere", "center": [160, 160, 160], "radius": 80}]}})");
  EXPECT_EQ(run_cli("validate " + (dir / "ok.json"), &out), 0) << out;
  EXPECT_EQ(run_cli("generate " + (dir / "ok.json") + " --set shape.blend=-3 -o " + (dir / "x.vdb"), &out), 1) << out;
  EXPECT_NE(out.find("/shape/blend: -3 is out of range"), std::string::npos) << out;
  EXPECT_EQ(run_cli("generate " + (dir / "ok.json") + " -q --set shape.sources.0.radius=60 -o " + (dir / "x.vdb"), &out), 0) << out;
  EXPECT_TRUE(std::filesystem::exists(dir / "x.vdb"));
}

// The proofs skipping and the tiling check rest on: wherever zero_in_ball says so, s is 0 at every
// point of the ball, and s is 0 outside support_box, for long, flat and turned ellipsoids, capsules
// and spheres, blended; and the smooth minimum never exceeds the minimum nor falls below it by more
// than blend / 4.
TEST(Shape, BallBoundIsConservative) {
  testutil::Lcg uni{12345};
  size_t proven = 0, in_cloud = 0;
  for (int trial = 0; trial < 40; ++trial) {
    ShapeParams sp;
    sp.blend = trial % 3 ? uni(0, 200) : 0;
    sp.falloff = uni(1, 300);
    for (int k = 0; k < 1 + trial % 4; ++k) {
      ShapeSource s;
      s.kind = ShapeKind((trial + k) % 3);
      const ShapeVec c{uni(-300, 300), uni(-300, 300), uni(-300, 300)};
      if (*s.kind == ShapeKind::Capsule) s.a = c, s.b = ShapeVec{c[0] + uni(-200, 200), c[1], c[2] + uni(-200, 200)};
      else s.center = c;
      if (*s.kind == ShapeKind::Ellipsoid) s.radii = ShapeVec{uni(5, 400), uni(5, 60), uni(5, 200)};
      else s.radius = uni(5, 150);
      s.rotate = {uni(-180, 180), uni(-180, 180), uni(-180, 180)};
      if (*s.kind != ShapeKind::Capsule) s.scale = {uni(0.5, 2), uni(0.5, 2), uni(0.5, 2)};
      sp.sources.push_back(s);
    }
    ASSERT_TRUE(shape_problems(sp).empty());
    const ShapeField f(sp);
    const auto box = f.support_box();
    for (int q = 0; q < 4000; ++q) {  // cloud never outside the support box
      const ShapeVec p{uni(-1500, 1500), uni(-1500, 1500), uni(-1500, 1500)};
      if (!(f.density(p) > 0)) continue;
      ++in_cloud;
      for (int a = 0; a < 3; ++a) ASSERT_TRUE(p[a] > box[0][a] && p[a] < box[1][a]) << "trial " << trial << " axis " << a;
    }
    for (int b = 0; b < 200; ++b) {
      const ShapeVec c{uni(-900, 900), uni(-900, 900), uni(-900, 900)};
      const double r = uni(0, 150);
      if (!f.zero_in_ball(c, r)) continue;
      ++proven;
      for (int q = 0; q < 50; ++q) {
        ShapeVec d{uni(-1, 1), uni(-1, 1), uni(-1, 1)};
        const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), t = q == 0 ? 1.0 : uni(0, 1);
        const ShapeVec p{c[0] + d[0] / l * r * t, c[1] + d[1] / l * r * t, c[2] + d[2] / l * r * t};
        ASSERT_EQ(f.density(p), 0.0) << "trial " << trial << " ball " << b;
      }
    }
  }
  EXPECT_GT(proven, 1000u);
  EXPECT_GT(in_cloud, 1000u);
  for (int i = 0; i < 1000; ++i) {
    const double a = uni(-100, 100), b = uni(-100, 100), k = uni(0, 80), m = smooth_min(a, b, k);
    EXPECT_LE(m, std::min(a, b));
    EXPECT_GE(m, std::min(a, b) - k / 4 - 1e-12);
  }
}

// Sources at the ends of their ranges (tiny and huge radii, far centres, hard and endless falloff,
// endless blend): values stay finite and in [0, 1], and skipping still changes nothing.
TEST(Shape, ExtremeSourcesStayFiniteAndExact) {
  const std::vector<std::string> shapes = {
      R"({"falloff": 0.001, "sources": [{"kind": "sphere", "center": [160, 160, 160], "radius": 0.001}]})",
      R"({"falloff": 0.001, "blend": 1e9, "sources": [{"kind": "ellipsoid", "center": [160, 160, 160], "radii": [1e9, 0.001, 1e9]},
                                                    {"kind": "capsule", "a": [0, 0, 0], "b": [0, 0, 0], "radius": 100}]})",
      R"({"falloff": 1e9, "sources": [{"kind": "ellipsoid", "center": [-1e9, 1e9, -1e9], "radii": [0.001, 1e9, 0.001],
                                       "scale": [1000, 0.001, 1000], "rotate": [360, -360, 45]}]})",
      R"({"falloff": 50, "blend": 1e9, "sources": [{"kind": "sphere", "center": [100, 100, 100], "radius": 50},
                                                  {"kind": "sphere", "center": [200, 200, 200], "radius": 50},
                                                  {"kind": "capsule", "a": [1e9, 0, 0], "b": [-1e9, 0, 0], "radius": 1e9}]})",
  };
  for (const std::string& sh : shapes) {
    SCOPED_TRACE(sh);
    const Preset p = parse_preset(R"({"resolution": [32, 32, 32], "voxel_size": 10, "tiling": false, "shape": )" + sh + "}", "x.json");
    GenerateOptions off;
    off.skip_empty = false;
    const Volume a = generate(p), b = generate(p, off);
    for (float d : a.density) ASSERT_TRUE(d >= 0.0f && d <= 1.0f);
    EXPECT_TRUE(same_bytes(a.density, b.density));
  }
}

// The placement convention the docs state: right-handed degrees about x, then y, then z (fixed
// axes), about the source's centre, after scale, before translate. An ellipsoid long along its own
// y (radii 10, 100, 10) must end up long along the axis each rotation predicts.
TEST(Shape, RotationsFollowTheStatedConvention) {
  struct Case {
    ShapeVec rotate, scale, translate;
    int long_axis;   ///< world axis of the tip at 100 m (times the scale) from the centre
    double length;   ///< the tip's distance from the placed centre
  };
  const std::vector<Case> cases = {
      {{0, 0, 0}, {1, 1, 1}, {0, 0, 0}, 1, 100},
      {{90, 0, 0}, {1, 1, 1}, {0, 0, 0}, 2, 100},    // +y turns to +z about x
      {{0, 0, 90}, {1, 1, 1}, {0, 0, 0}, 0, 100},    // +y turns to -x about z
      {{90, 90, 0}, {1, 1, 1}, {0, 0, 0}, 0, 100},   // x first (+y to +z), then y (+z to +x)
      {{0, 0, 90}, {1, 3, 1}, {7, -5, 2}, 0, 300},   // scaled along its own y first, moved last
  };
  for (const Case& c : cases) {
    ShapeParams sp;
    ShapeSource s;
    s.kind = ShapeKind::Ellipsoid;
    s.center = ShapeVec{50, 60, 70};
    s.radii = ShapeVec{10, 100, 10};
    s.rotate = c.rotate, s.scale = c.scale, s.translate = c.translate;
    sp.sources = {s};
    const ShapeField f(sp);
    const ShapeVec m{50 + c.translate[0], 60 + c.translate[1], 70 + c.translate[2]};
    for (int a = 0; a < 3; ++a)
      for (double sign : {-1.0, 1.0}) {
        ShapeVec p = m;
        p[a] += sign * c.length;
        const double d = f.distance(p);
        SCOPED_TRACE("rotate " + std::to_string(c.rotate[0]) + "," + std::to_string(c.rotate[1]) + "," +
                     std::to_string(c.rotate[2]) + " axis " + std::to_string(a));
        if (a == c.long_axis) EXPECT_NEAR(d, 0.0, 1e-6);
        else EXPECT_GT(d, 0.5 * c.length);
      }
  }
}

// shape.floor and shape.ceiling cut the union flat (a cumulus's base, an anvil's top): with the
// noise neutralised the cloud is the sphere's interior between the two heights, skipping stays
// exact, and a ceiling below the floor is refused.
TEST(Shape, FloorAndCeilingCutFlat) {
  const std::string shape = R"({"falloff": 100, "floor": 250, "ceiling": 420,
      "sources": [{"kind": "sphere", "center": [320, 320, 320], "radius": 200}]})";
  const Volume v = generate(shaped(shape, true));
  const double i = iou(v, [](double x, double y, double z) { return std::hypot(x - 320, y - 320, z - 320) < 200 && y > 250 && y < 420; });
  std::printf("  cut sphere: IoU %.4f\n", i);
  EXPECT_GE(i, 0.99);
  const Preset eroded = shaped(shape, false);
  GenerateOptions on, off;
  off.skip_empty = false;
  GenerateStats st;
  const Volume a = generate(eroded, on, &st), b = generate(eroded, off);
  EXPECT_TRUE(same_bytes(a.density, b.density));
  EXPECT_GT(st.bricks_skipped, 0u);
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x)
        if (a.density[a.index(x, y, z)] > 0) {
          ASSERT_TRUE(centre(y) > 200 && centre(y) < 470) << y;
        }
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"floor": 500, "ceiling": 400, "sources": [{"kind": "sphere", "center": [0, 0, 0], "radius": 3}]}})")
                .find("/shape/ceiling: 400 must be above /shape/floor (500)"),
            std::string::npos);
}
