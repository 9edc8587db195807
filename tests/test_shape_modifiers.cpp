// The billowy and wispy shape modifiers (cloudgen/shape.h ShapeModifier): billowy moves the surface
// out by at most its amplitude and wispy erodes it in by at most its amplitude, each only where its
// height ramp and depth mask allow (wispy mostly downwind); the skipping proofs still hold, so
// skipped and unskipped runs, thread counts and regions give the same bytes; the preset table
// knows the keys (validation names field and range), and presets without modifiers keep their
// hash.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "cloudgen/generate.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/preset.h"
#include "cloudgen/shape.h"
#include "test_util.h"
#include "test_util_generate.h"

using namespace cloudgen;
using testutil::same_bytes;

namespace {

using Rng = testutil::Lcg;

/// One sphere of radius 200 m at (320, 320, 320), falloff 100 m.
ShapeParams sphere() {
  ShapeParams sp;
  sp.falloff = 100;
  ShapeSource s;
  s.kind = ShapeKind::Sphere;
  s.center = ShapeVec{320, 320, 320};
  s.radius = 200;
  sp.sources.push_back(s);
  return sp;
}

/// A point at distance `r` from the sphere's centre in a random direction.
ShapeVec around(Rng& u, double r) {
  double d[3], l = 0;
  do {
    l = 0;
    for (double& c : d) c = u(-1, 1), l += c * c;
  } while (l > 1 || l < 1e-4);
  l = std::sqrt(l);
  return {320 + d[0] / l * r, 320 + d[1] / l * r, 320 + d[2] / l * r};
}

/// A 64^3 preset of 10 m voxels: the sphere with `mods` (JSON members of "shape") and the noise
/// neutralised (R = 1, threshold 0.5: density > 0 exactly where d' < 0).
Preset neutral_sphere(const std::string& mods, const std::string& extra = "") {
  return parse_preset(R"({"resolution": [64, 64, 64], "voxel_size": 10, "tiling": false, "threshold": 0.5,
      "channels": {"r": {"remap": [-1, -0.5]}},
      "shape": {"falloff": 100, "sources": [{"kind": "sphere", "center": [320, 320, 320], "radius": 200}])" +
                          mods + "}" + extra + "}",
                      "mods.json");
}

}  // namespace

// Billowy: d' in [d - A, d] everywhere, the full range used near the surface (the billows rise to
// most of A and fall to 0 between), and the generated cloud holds the whole sphere and stays within
// A of it.
TEST(ShapeModifiers, BillowyMovesTheSurfaceOutWithinItsAmplitude) {
  ShapeParams sp = sphere();
  sp.billowy.amplitude = 60, sp.billowy.period = 120;
  const ShapeField f(sp, 10, 7);
  Rng u{1};
  double lo = 1e9, hi = -1e9;
  for (int i = 0; i < 4000; ++i) {
    const ShapeVec p = around(u, u(150, 320));
    const double d = f.distance(p), m = f.modified_distance(p);
    ASSERT_LE(m, d) << i;
    ASSERT_GE(m, d - 60) << i;
    if (d > -20) lo = std::min(lo, d - m), hi = std::max(hi, d - m);  // within the depth mask's full weight
  }
  std::printf("  billowy lift near the surface: %.1f .. %.1f m of 60\n", lo, hi);
  EXPECT_GT(hi, 45.0);
  EXPECT_LT(lo, 25.0);

  const Volume plain = generate(neutral_sphere("")),
               billowy = generate(neutral_sphere(R"(, "billowy": {"amplitude": 60, "period": 120})"));
  size_t n_plain = 0, n_billowy = 0, lost = 0, beyond = 0;
  for (uint32_t z = 0; z < 64; ++z)
    for (uint32_t y = 0; y < 64; ++y)
      for (uint32_t x = 0; x < 64; ++x) {
        const size_t i = plain.index(x, y, z);
        const double r = std::hypot((x + 0.5) * 10 - 320, (y + 0.5) * 10 - 320, (z + 0.5) * 10 - 320);
        n_plain += plain.density[i] > 0, n_billowy += billowy.density[i] > 0;
        lost += plain.density[i] > 0 && !(billowy.density[i] > 0);
        beyond += billowy.density[i] > 0 && r >= 260;
      }
  std::printf("  voxels: sphere %zu, billowy %zu\n", n_plain, n_billowy);
  EXPECT_EQ(lost, 0u);
  EXPECT_EQ(beyond, 0u);
  EXPECT_GT(n_billowy, n_plain + n_plain / 5);  // a 30 m mean lift on 200 m: about +45%
}

// Wispy: d' in [d, d + A], and with downwind 1 the upwind side (facing against the wind) keeps
// far less of it than the downwind side.
TEST(ShapeModifiers, WispyErodesInwardMostlyDownwind) {
  ShapeParams sp = sphere();
  sp.wispy.amplitude = 60, sp.wispy.period = 100, sp.wispy.downwind = 1, sp.wispy.wind = {1, 0, 0};
  const ShapeField f(sp, 10, 7);
  Rng u{2};
  double up = 0, down = 0;
  size_t nu = 0, nd = 0;
  for (int i = 0; i < 6000; ++i) {
    const ShapeVec p = around(u, u(170, 230));
    const double d = f.distance(p), m = f.modified_distance(p);
    ASSERT_GE(m, d) << i;
    ASSERT_LE(m, d + 60) << i;
    if (p[0] < 320 - 120) up += m - d, ++nu;
    if (p[0] > 320 + 120) down += m - d, ++nd;
  }
  up /= double(nu), down /= double(nd);
  std::printf("  mean erosion: upwind %.2f m, downwind %.2f m\n", up, down);
  EXPECT_GT(down, 8.0);
  EXPECT_LT(up, down / 3);
}

// The height ramp and the depth mask: no billows below heights[0], no wisps deeper than depth.
TEST(ShapeModifiers, HeightRampAndDepthMaskConfineThem) {
  ShapeParams sp = sphere();
  sp.billowy.amplitude = 60, sp.billowy.period = 120, sp.billowy.heights = std::array<double, 2>{320, 420};
  sp.wispy.amplitude = 60, sp.wispy.period = 100, sp.wispy.depth = 50, sp.wispy.downwind = 0;
  sp.wispy.heights = std::array<double, 2>{320, 200};  // full below 200 m, none above 320 m
  const ShapeField f(sp, 10, 3);
  Rng u{3};
  size_t below = 0, above = 0, moved_above = 0;
  for (int i = 0; i < 4000; ++i) {
    const ShapeVec p = around(u, u(100, 300));
    const double d = f.distance(p), m = f.modified_distance(p);
    if (p[1] <= 320 && d <= -50) {
      ASSERT_EQ(m, d) << "no billows below 320 m, no wisps deeper than 50 m";
    }
    if (p[1] >= 320) {
      ASSERT_LE(m, d) << "no wisps above 320 m";
      ++above, moved_above += m < d;
    } else {
      ++below;
    }
  }
  EXPECT_GT(below, 1000u);
  EXPECT_GT(moved_above, above / 2);
}

// Skipping rests on zero_in_ball and support_box: with both modifiers, s is 0 wherever they say so,
// and the generated bytes are those of an unskipped run, at any thread count and in a region.
TEST(ShapeModifiers, SkippingStaysExact) {
  ShapeParams sp = sphere();
  sp.sources.push_back(sp.sources[0]);
  sp.sources[1].center = ShapeVec{450, 250, 300}, sp.sources[1].radius = 90;
  sp.blend = 80, sp.floor = 180, sp.ceiling = 560;
  sp.billowy.amplitude = 70, sp.billowy.period = 150;
  sp.wispy.amplitude = 50, sp.wispy.period = 90;
  const ShapeField f(sp, 10, 11);
  const auto box = f.support_box();
  Rng u{4};
  size_t proven = 0, in_cloud = 0;
  for (int q = 0; q < 6000; ++q) {
    const ShapeVec p{u(-200, 900), u(-200, 900), u(-200, 900)};
    if (!(f.density(p) > 0)) continue;
    ++in_cloud;
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(p[a] > box[0][a] && p[a] < box[1][a]) << a;
  }
  for (int b = 0; b < 400; ++b) {
    const ShapeVec c{u(-200, 900), u(-200, 900), u(-200, 900)};
    const double r = u(0, 120);
    if (!f.zero_in_ball(c, r)) continue;
    ++proven;
    for (int q = 0; q < 40; ++q) {
      Rng v{uint64_t(b * 100 + q)};
      const ShapeVec d = around(v, r * v(0, 1));
      ASSERT_EQ(f.density({c[0] + d[0] - 320, c[1] + d[1] - 320, c[2] + d[2] - 320}), 0.0) << b;
    }
  }
  EXPECT_GT(proven, 100u);
  EXPECT_GT(in_cloud, 100u);

  const Preset p = parse_preset(R"({"resolution": [80, 64, 72], "voxel_size": 10, "tiling": false,
      "channels": {"g": {"enabled": true}},
      "shape": {"blend": 80, "falloff": 100, "floor": 180, "ceiling": 560,
        "billowy": {"amplitude": 70, "period": 150, "heights": [150, 500]},
        "wispy": {"amplitude": 50, "period": 90, "heights": [400, 150], "wind": [1, 0, 1]},
        "sources": [{"kind": "sphere", "center": [320, 320, 320], "radius": 200},
                    {"kind": "capsule", "a": [450, 250, 300], "b": [600, 300, 400], "radius": 70}]}})",
                                "mods.json");
  GenerateStats st;
  const Volume a = testutil::generate_every_way(p, st);
  EXPECT_GT(st.bricks_skipped, 0u);
  EXPECT_GT(st.active_voxels, 0u);
  GenerateOptions r;
  r.region_origin = {9, 13, 5};
  r.region_extent = {41, 30, 50};
  const Volume part = generate(p, r);
  for (uint32_t z = 0; z < 50; ++z)
    for (uint32_t y = 0; y < 30; ++y)
      for (uint32_t x = 0; x < 41; ++x) ASSERT_EQ(part.density[part.index(x, y, z)], a.density[a.index(x + 9, y + 13, z + 5)]);
}

// The seed moves the billows; a modifier at amplitude 0 changes neither bytes nor hash (the shipped
// presets keep their checksums), one that is on changes the hash.
TEST(ShapeModifiers, SeedAndHash) {
  const std::string mods = R"(, "billowy": {"amplitude": 60, "period": 120})";
  const Preset a = neutral_sphere(mods), b = neutral_sphere(mods, R"(, "seed": 2)");
  EXPECT_FALSE(same_bytes(generate(a).density, generate(b).density));
  const Preset plain = neutral_sphere(""), off = neutral_sphere(R"(, "billowy": {"period": 50}, "wispy": {"gain": 0.3})");
  EXPECT_EQ(preset_hash(plain), preset_hash(off));
  EXPECT_TRUE(same_bytes(generate(plain).density, generate(off).density));
  EXPECT_NE(preset_hash(plain), preset_hash(a));
  EXPECT_NE(preset_hash(a), preset_hash(neutral_sphere(R"(, "billowy": {"amplitude": 60, "period": 120, "octaves": 2})")));
}

// Bad input names the field and what is allowed.
TEST(ShapeModifiers, BadInputNamesTheFieldAndRange) {
  auto error_of = [](const std::string& json) -> std::string {
    try {
      parse_preset(json, "bad.json");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  const std::string sphere = R"("sources": [{"kind": "sphere", "center": [0, 0, 0], "radius": 50}])";
  EXPECT_NE(error_of(R"({"shape": {"billowy": {"amplitude": 50}}})").find("/shape/billowy/amplitude: 50 needs shape sources"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"wispy": {"amplitude": 5, "octaves": 9}, )" + sphere + "}}")
                .find("/shape/wispy/octaves"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"billowy": {"amplitude": -1}, )" + sphere + "}}").find("/shape/billowy/amplitude"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"billowy": {"warp": 1}, )" + sphere + "}}").find("/shape/billowy/warp: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"tiling": false, "shape": {"wispy": {"heights": [1]}, )" + sphere + "}}").find("/shape/wispy/heights"),
            std::string::npos);
}

// The floor and the ceiling cut after the modifiers: billows do not lift a flat base or top.
TEST(ShapeModifiers, CutsStayFlat) {
  const Volume v = generate(neutral_sphere(R"(, "floor": 250, "ceiling": 420, "billowy": {"amplitude": 60, "period": 120})"));
  size_t in = 0, at_floor = 0;
  for (uint32_t z = 0; z < 64; ++z)
    for (uint32_t y = 0; y < 64; ++y)
      for (uint32_t x = 0; x < 64; ++x)
        if (v.density[v.index(x, y, z)] > 0) {
          const double cy = (y + 0.5) * 10;
          ASSERT_TRUE(cy > 250 && cy < 420) << cy;
          ++in, at_floor += y == 25;
        }
  EXPECT_GT(in, 0u);
  // The base is a flat disc wider than the plain sphere's cut at 255 m: r = sqrt(200^2 - 65^2) = 189 m.
  EXPECT_GT(at_floor, size_t(M_PI * 189 * 189 / 100));
}

// A mesh's distance lattice holds the true distance out to its band and a constant beyond: the band
// must reach past what the billows can lift, or they lift that constant into specks of cloud far
// from the mesh (seen on a billowy torus before the band grew by the amplitude).
TEST(ShapeModifiers, BillowsOnAMeshStayNearIt) {
  std::vector<std::array<float, 3>> pts;
  for (int c = 0; c < 8; ++c) pts.push_back({c & 1 ? 500.f : 200.f, c & 2 ? 500.f : 200.f, c & 4 ? 500.f : 200.f});
  const std::vector<std::array<uint32_t, 3>> tris = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                                     {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  ShapeParams sp;
  sp.falloff = 40;
  ShapeSource s;
  s.kind = ShapeKind::Mesh;
  s.file = "cube.obj";
  s.mesh = std::make_shared<const TriangleMesh>(mesh_from_arrays(pts, tris, "cube"));
  sp.sources.push_back(s);
  sp.billowy.amplitude = 80, sp.billowy.period = 60, sp.billowy.depth = 20;
  const ShapeField f(sp, 10, 5);
  Rng u{6};
  size_t far = 0, near = 0;
  for (int i = 0; i < 20000; ++i) {
    const ShapeVec p{u(-300, 1000), u(-300, 1000), u(-300, 1000)};
    double o2 = 0;  // squared distance to the cube
    for (double c : p) {
      const double e = std::max({200 - c, c - 500, 0.0});
      o2 += e * e;
    }
    const double out = std::sqrt(o2);
    if (out > 20 + 80 + 2 * 10) {  // falloff / 2 + amplitude + the lattice's two samples
      ++far;
      ASSERT_EQ(f.density(p), 0.0) << p[0] << " " << p[1] << " " << p[2];
    } else if (out > 0 && out < 60) {
      near += f.density(p) > 0;
    }
  }
  EXPECT_GT(far, 10000u);
  EXPECT_GT(near, 100u) << "billows lift cloud out of the cube";
}

// A key that may be unset takes null, in a file or through --set, and then reads as unset.
TEST(ShapeModifiers, NullUnsetsAnOptionalKey) {
  const Preset a = load_preset(testutil::kPresets + "cumulus-congestus.json", {"shape.floor=null", "shape.wispy.heights=null"});
  EXPECT_FALSE(a.shape.floor.has_value());
  EXPECT_FALSE(a.shape.wispy.heights.has_value());
  const Preset b = load_preset(testutil::kPresets + "cumulus-congestus.json");
  ASSERT_TRUE(b.shape.floor.has_value());
  EXPECT_EQ(*b.shape.floor, 350);
  ASSERT_TRUE(b.shape.wispy.heights.has_value());
  EXPECT_NE(preset_hash(a), preset_hash(b));
  // A key that cannot be unset still refuses null, naming what it takes.
  try {
    load_preset(testutil::kPresets + "cumulus-congestus.json", {"shape.falloff=null"});
    ADD_FAILURE() << "null falloff accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/shape/falloff: null has the wrong type"), std::string::npos) << e.what();
  }
}
