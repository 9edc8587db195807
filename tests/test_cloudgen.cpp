// cloudgen: presets (parsing, errors), the pipeline's invariants (exact skipping, regions,
// threads, tiling, occupancy), exporters' round trips, atomic output and the CLI's behaviour.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "cloudgen/channel.h"
#include "cloudgen/budget.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/param_group.h"
#include "cloudgen/preset.h"
#include "cloudgen/scale.h"
#include "test_util.h"

using namespace cloudgen;
namespace fs = std::filesystem;

namespace {

using testutil::kCli;
using testutil::kPresets;
using testutil::read_text;
using testutil::run_cli;
using testutil::same_bytes;
using testutil::TempDir;

Preset preset(const std::string& name, std::vector<std::string> sets = {}) {
  return load_preset(kPresets + name + ".json", sets);
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

// ---------------------------------------------------------------------------------------------
TEST(Presets, EveryShippedPresetValidatesAndGenerates) {
  int n = 0;
  for (auto& e : fs::directory_iterator(kPresets)) {
    if (e.path().extension() != ".json") continue;
    ++n;
    SCOPED_TRACE(e.path().string());
    Preset p = load_preset(e.path().string());
    rescale(p, 40);  // same shapes, small enough for a unit test
    GenerateStats st;
    Volume v = generate(p, {}, &st);
    EXPECT_GT(st.active_voxels, 0u) << "preset generates an empty volume";
    EXPECT_LT(st.active_voxels, v.voxel_count()) << "preset fills the whole box";
    for (float d : v.density) ASSERT_TRUE(d >= 0.0f && d <= 1.0f);
  }
  for (const char* required : {"thesis", "cumulus", "cumulonimbus", "stratus", "cumulus-field", "tiny"})
    EXPECT_TRUE(fs::exists(kPresets + required + ".json")) << required;
  EXPECT_GE(n, 6);
  Preset field = preset("cumulus-field");
  EXPECT_EQ(field.resolution, (std::array<uint32_t, 3>{512, 128, 512}));
  Preset thesis = preset("thesis");
  EXPECT_EQ(thesis.resolution, (std::array<uint32_t, 3>{128, 128, 128}));
  EXPECT_EQ(thesis.channels[0].kind, noise3d::Kind::Worley);
  EXPECT_EQ(thesis.channels[0].octaves, 5);
  EXPECT_EQ(thesis.height_a, 50);
  EXPECT_EQ(thesis.height_b, 4);
}

TEST(Presets, BadPresetsGiveTheirSpecificError) {
  struct Case {
    std::string json, expect;
  };
  const std::vector<Case> cases = {
      {R"({"threshold": "high"})", "/threshold: \"high\" has the wrong type; expected a number"},
      {R"({"threshold": 1.5})", "/threshold: 1.5 is out of range; allowed: number in [0, 0.999]"},
      {R"({"channels": {"r": {"octaves": 40}}})", "/channels/r/octaves: 40 is out of range"},
      {R"({"channels": {"r": {"octaves": 2.5}}})", "/channels/r/octaves: 2.5 has the wrong type; expected an integer"},
      {R"({"treshold": 0.3})", "/treshold: unknown key (did you mean \"threshold\"?)"},
      {R"({"channels": {"q": {}}})", "/channels/q: unknown key"},
      {R"({"channels": {"r": {"kind": "simplex"}}})", "expected one of: perlin | worley | perlin-worley"},
      {R"({"resolution": [64, 64]})", "/resolution: [64,64] has the wrong type; expected an array of 3 integers"},
      {R"({"resolution": [64, 0, 64]})", "/resolution/1: 0 is out of range"},
      {R"({"towers": {"list": [{"center": [0.02, 0.2, 0.5]}]}})", "/towers/list/0: centre x +- 3 sigma"},
      {R"({"towers": {"list": [{"centre": [0.5, 0.2, 0.5]}]}})", "/towers/list/0/centre: unknown key (did you mean \"center\"?)"},
      {R"({"coverage": {"low": 0.7, "high": 0.6}})", "/coverage/high: 0.6 must be greater than /coverage/low"},
      {R"({"channels": {"r": {"period": 65536, "octaves": 16}}})", "/channels/r: octaves: period * lacunarity^(octaves-1)"},
      {"{\n  \"seed\": 1,\n  \"threshold\": 0.3,,\n}", "JSON syntax error at line 3, column 20"},
      {R"([1, 2])", "the preset must be a JSON object"},
      {R"({"channels": {"r": {"remap": [0.9, 0.8]}}})", "/channels/r/remap: lo must be below hi"},
      {R"({"channels": {"r": {"remap": [0.9]}}})", "/channels/r/remap: [0.9] has the wrong type; expected an array of 2 numbers"},
      {"999999999999999999999999991e5000000.9[ ", "invalid JSON"},  // found by fuzz_preset
  };
  for (const Case& c : cases) {
    std::string e = error_of(c.json);
    EXPECT_NE(e.find("bad.json"), std::string::npos) << "error must name the file: " << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << "for " << c.json << "\n got: " << e << "\n want: " << c.expect;
  }
  // Every problem is listed, not only the first.
  std::string e = error_of(R"({"threshold": 7, "sed": 1, "voxel_size": -1})");
  EXPECT_NE(e.find("/threshold"), std::string::npos);
  EXPECT_NE(e.find("/sed"), std::string::npos);
  EXPECT_NE(e.find("/voxel_size"), std::string::npos);
}

TEST(Presets, SetOverridesGoThroughTheSameValidation) {
  Preset p = parse_preset("{}", "x.json", {"seed=7", "channels.r.octaves=6", "resolution=[16,8,16]", "height.profile=stratus"});
  EXPECT_EQ(p.seed, 7u);
  EXPECT_EQ(p.channels[0].octaves, 6);
  EXPECT_EQ(p.resolution, (std::array<uint32_t, 3>{16, 8, 16}));
  EXPECT_STREQ(height_profile_name(p.height_profile), "stratus");
  EXPECT_NE(error_of("{}", {"threshold=2"}).find("/threshold: 2 is out of range"), std::string::npos);
  EXPECT_NE(error_of("{}", {"channels.r.octavs=2"}).find("did you mean \"octaves\""), std::string::npos);
  EXPECT_NE(error_of("{}", {"noequals"}).find("expected key.path=value"), std::string::npos);
}

TEST(Presets, RescaleKeepsProportionsAndWorldSize) {
  Preset p = preset("cumulus-field");
  const auto world = std::array<double, 3>{p.resolution[0] * p.voxel_size, p.resolution[1] * p.voxel_size,
                                           p.resolution[2] * p.voxel_size};
  rescale(p, 128);
  EXPECT_EQ(p.resolution, (std::array<uint32_t, 3>{128, 32, 128}));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(p.resolution[a] * p.voxel_size, world[a], 1e-9);
}

// Every preset key has a group (cloudgen/param_group.h) for the panel and the docs; the docs list
// the groups in their one order, each key under its own group's heading.
TEST(Presets, EveryKeyHasAGroupAndTheDocsListThem) {
  const std::string md = params_markdown();
  for (const auto& pi : params()) {
    const ParamPlace place = preset_param_place(pi.pointer);
    ASSERT_NE(place.group, ParamGroup::Unset) << pi.pointer;
    std::string key = pi.pointer.substr(1);
    std::replace(key.begin(), key.end(), '/', '.');
    const std::string heading = std::string(place.advanced ? "### " : "## ") + param_group_name(place.group) +
                                (place.advanced ? ": advanced" : "") + "\n";
    const size_t h = md.find(heading), k = md.find("| `" + key + "` |");
    ASSERT_NE(h, std::string::npos) << heading;
    ASSERT_NE(k, std::string::npos) << key;
    EXPECT_GT(k, h) << key;
    const size_t next = md.find("\n#", h + 1);
    EXPECT_TRUE(next == std::string::npos || k < next) << key << " is not under " << heading;
  }
  EXPECT_EQ(preset_param_place("/threshold").group, ParamGroup::Shape);
  EXPECT_EQ(preset_param_place("/channels/g/octaves").group, ParamGroup::Detail);
  EXPECT_EQ(preset_param_place("/view/fov").group, ParamGroup::Camera);
  EXPECT_EQ(preset_param_place("/motion/flow_map").group, ParamGroup::Animation);
  EXPECT_TRUE(preset_param_place("/occupancy/cell").advanced);
  EXPECT_EQ(preset_param_place("/no/such/key").group, ParamGroup::Unset);
  size_t pos = 0;
  for (ParamGroup g : kParamGroups) {
    const size_t at = md.find(std::string("## ") + param_group_name(g) + "\n");
    ASSERT_NE(at, std::string::npos) << param_group_name(g);
    EXPECT_GE(at, pos);
    pos = at;
  }
}

TEST(Presets, DocsAreGeneratedFromTheTable) {
  std::string md = params_markdown();
  for (const auto& pi : params()) {
    std::string key = pi.pointer.substr(1);
    std::replace(key.begin(), key.end(), '/', '.');
    EXPECT_NE(md.find("`" + key + "`"), std::string::npos) << key;
  }
  // docs/presets.md must be the table's current text (regenerate with scripts/gen_docs.sh).
  std::ifstream in(std::string(CLOUD_SOURCE_DIR) + "/docs/presets.md");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find(md), std::string::npos) << "docs/presets.md is out of date with the parameter table";
}

// ---------------------------------------------------------------------------------------------
TEST(Pipeline, SkippingDoesNotChangeASingleValue) {
  for (const char* name : {"tiny", "thesis", "cumulus-field", "cumulus"}) {
    SCOPED_TRACE(name);
    Preset p = preset(name);
    rescale(p, 96);
    GenerateOptions on, off;
    off.skip_empty = false;
    GenerateStats s_on, s_off;
    Volume a = generate(p, on, &s_on), b = generate(p, off, &s_off);
    EXPECT_TRUE(same_bytes(a.density, b.density));
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bytes(a.detail[c], b.detail[c]));
    EXPECT_EQ(s_off.bricks_skipped, 0u);
    if (std::string(name) == "cumulus-field") {
      EXPECT_GT(s_on.bricks_skipped, s_on.bricks / 2);
    }
  }
}

// Detail channels are skipped where the bound proves that no voxel within one voxel can hold
// cloud; everywhere the renderer's trilinear filter can read them next to cloud (the density's
// non-zero voxels dilated by their 26 neighbours, wrapping x and z in tiling volumes) they must
// equal the channel's noise exactly.
TEST(Pipeline, DetailIsExactWithinOneVoxelOfCloud) {
  for (const char* name : {"tiny", "thesis", "cumulus", "cumulus-field"}) {
    SCOPED_TRACE(name);
    Preset p = preset(name);
    rescale(p, 96);
    GenerateStats st;
    Volume v = generate(p, {}, &st);
    const auto N = v.dims;
    std::vector<uint8_t> mask(v.voxel_count(), 0);
    size_t masked = 0;
    for (uint32_t z = 0; z < N[2]; ++z)
      for (uint32_t y = 0; y < N[1]; ++y)
        for (uint32_t x = 0; x < N[0]; ++x) {
          if (v.density[v.index(x, y, z)] <= 0) continue;
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                int64_t q[3] = {int64_t(x) + dx, int64_t(y) + dy, int64_t(z) + dz};
                if (q[1] < 0 || q[1] >= N[1]) continue;
                bool out = false;
                for (int a : {0, 2}) {
                  if (q[a] >= 0 && q[a] < N[a]) continue;
                  if (v.tiles_xz) q[a] = (q[a] + N[a]) % N[a];
                  else out = true;
                }
                if (out) continue;
                uint8_t& m = mask[v.index(uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2]))];
                masked += !m;
                m = 1;
              }
        }
    ASSERT_GT(masked, 0u);
    size_t zero_outside = 0;
    for (int c = 1; c < 4; ++c) {
      if (!p.channels[c].enabled) continue;
      const Channel& ch = p.channels[c];
      // The presets' detail channels are plain Worley in [0, 1]: the value is the clamped noise.
      ASSERT_TRUE(ch.kind == noise3d::Kind::Worley && !ch.invert && ch.remap[0] == 0.0 && ch.remap[1] == 1.0);
      std::vector<float> ref(v.voxel_count());
      noise3d::GridRegion g;
      g.size = N;
      noise3d::evaluate_grid(channel_params(p, c), g, ref.data());
      const std::vector<float>& d = v.detail[c - 1];
      ASSERT_EQ(d.size(), ref.size());
      for (size_t i = 0; i < ref.size(); ++i) {
        if (mask[i]) {
          ASSERT_EQ(d[i], std::clamp(ref[i], 0.0f, 1.0f)) << "channel " << c << " voxel " << i;
        } else {
          zero_outside += d[i] == 0.0f;
        }
      }
    }
    // And the skipping happened: detail was evaluated in fewer bricks than the volume has.
    if (std::string(name) != "tiny") {
      EXPECT_LT(st.detail_bricks, st.bricks);
      EXPECT_GT(zero_outside, 0u);
    }
  }
}

// A plan executed in any split (here: two interleaved halves, each with its own thread count)
// gives the bytes of generate(): what MPI ranks and farm tiles rely on.
TEST(Pipeline, PlanSplitIntoPartsGivesTheSameBytes) {
  Preset p = preset("thesis");
  rescale(p, 64);
  const Volume full = generate(p);
  const BrickPlan plan = plan_bricks(p);
  ASSERT_EQ(plan.bricks.size(), 4u * 4u * 4u);
  Volume v = volume_header(p, plan);
  EXPECT_EQ(v.metadata, full.metadata);
  v.density.assign(v.voxel_count(), 0.0f);
  v.detail[0].assign(v.voxel_count(), 0.0f);
  std::mutex mtx;
  auto sink = [&](size_t b, BrickResult& r) {
    std::lock_guard<std::mutex> lock(mtx);
    const PlannedBrick& bx = plan.bricks[b];
    size_t k = 0;
    for (uint32_t z = bx.lo[2]; z < bx.hi[2]; ++z)
      for (uint32_t y = bx.lo[1]; y < bx.hi[1]; ++y)
        for (uint32_t x = bx.lo[0]; x < bx.hi[0]; ++x, ++k) {
          v.density[v.index(x, y, z)] = r.density[k];
          if (!r.detail[0].empty()) v.detail[0][v.index(x, y, z)] = r.detail[0][k];
        }
  };
  std::vector<size_t> even, odd;
  for (size_t b = 0; b < plan.bricks.size(); ++b) (b % 2 ? odd : even).push_back(b);
  GenerateOptions one, two;
  one.threads = 1, two.threads = 2;
  GenerateStats se, so;
  execute_plan(p, plan, &even, one, sink, &se);
  execute_plan(p, plan, &odd, two, sink, &so);
  // An empty share (an MPI rank with more ranks than bricks) generates nothing.
  GenerateStats s0;
  const std::vector<size_t> none;
  execute_plan(p, plan, &none, one, [](size_t, BrickResult&) { FAIL() << "a brick of an empty share"; }, &s0);
  EXPECT_EQ(s0.bricks, 0u);
  EXPECT_EQ(se.bricks + so.bricks, plan.bricks.size());
  EXPECT_TRUE(same_bytes(v.density, full.density));
  EXPECT_TRUE(same_bytes(v.detail[0], full.detail[0]));
  // Expected cost: a brick the bound skips is planned cheaper than one whose noise is evaluated.
  double c_skip = 0, c_full = 0;
  for (const PlannedBrick& b : plan.bricks) (b.density ? c_full : c_skip) = b.cost;
  EXPECT_GT(c_skip, 0.0);
  EXPECT_LT(c_skip, c_full);
}

// The MPI split: every brick on exactly one rank, deterministic, and no rank above the greedy
// (longest-first) bound of the mean load plus one brick.
TEST(Scale, BalanceCoversEveryBrickOnceWithinTheGreedyBound) {
  Preset p = preset("cumulus-field");
  rescale(p, 128);
  const BrickPlan plan = plan_bricks(p);
  double total = 0, biggest = 0;
  for (const auto& b : plan.bricks) total += b.cost, biggest = std::max(biggest, b.cost);
  for (int n : {1, 2, 3, 7}) {
    SCOPED_TRACE(n);
    const auto parts = balance_bricks(plan, n);
    EXPECT_EQ(parts, balance_bricks(plan, n));
    ASSERT_EQ(parts.size(), size_t(n));
    std::vector<int> seen(plan.bricks.size(), 0);
    for (const auto& part : parts) {
      double load = 0;
      for (size_t b : part) ++seen[b], load += plan.bricks[b].cost;
      EXPECT_LE(load, total / n + biggest + 1e-9);
    }
    for (int s : seen) ASSERT_EQ(s, 1);
  }
  EXPECT_THROW(balance_bricks(plan, 0), InputError);
}

// Two writes of one volume are the same bytes: the file UUID is derived from the content, not
// OpenVDB's random one (issue 47, item 8), and another volume gets another UUID. Tile checksums
// still skip the UUID (tiles of other writers carry random ones) and see one flipped bit.
TEST(Scale, TileChecksumIsTheSameForTheSameVolumeAndSeesDamage) {
  TempDir dir;
  Preset p = preset("tiny");
  Volume v = generate(p);
  write_vdb(v, dir / "a.vdb", {});
  write_vdb(v, dir / "b.vdb", {});
  std::ifstream fa(dir / "a.vdb", std::ios::binary), fb(dir / "b.vdb", std::ios::binary);
  std::string ba((std::istreambuf_iterator<char>(fa)), {}), bb((std::istreambuf_iterator<char>(fb)), {});
  ASSERT_EQ(ba.size(), bb.size());
  EXPECT_EQ(ba, bb) << "the same volume must give the same bytes, UUID included";
  Preset q = p;
  q.seed = 4;
  write_vdb(generate(q), dir / "other.vdb", {});
  const std::string other = read_text(dir / "other.vdb");
  ASSERT_GT(other.size(), 57u);
  EXPECT_NE(other.substr(21, 36), ba.substr(21, 36)) << "another volume, another UUID";
  EXPECT_EQ(ba[21 + 14], '5') << "a name-based (version 5) UUID: " << ba.substr(21, 36);
  EXPECT_EQ(file_checksum(dir / "a.vdb"), file_checksum(dir / "b.vdb"));
  ba[ba.size() / 2] ^= 1;
  std::ofstream(dir / "c.vdb", std::ios::binary) << ba;
  EXPECT_NE(file_checksum(dir / "a.vdb"), file_checksum(dir / "c.vdb"));
  EXPECT_THROW(file_checksum(dir / "missing.vdb"), IoError);
  const VdbHeader h = read_vdb_header(dir / "a.vdb");
  EXPECT_EQ(h.meta("preset_hash"), preset_hash(p));
  EXPECT_EQ(h.meta("seed"), "3");
  EXPECT_DOUBLE_EQ(h.origin[0], p.origin[0]);
}

TEST(Pipeline, IdenticalAcrossThreadCountsAndRegions) {
  Preset p = preset("thesis");
  rescale(p, 64);
  GenerateOptions one, two;
  one.threads = 1, two.threads = 2;
  Volume a = generate(p, one), b = generate(p, two);
  EXPECT_TRUE(same_bytes(a.density, b.density));
  EXPECT_TRUE(same_bytes(a.detail[0], b.detail[0]));
  // A region that is not brick-aligned gives the full run's values at the same voxels.
  GenerateOptions r;
  r.region_origin = {5, 13, 21};
  r.region_extent = {37, 29, 19};
  Volume part = generate(p, r);
  EXPECT_EQ(part.dims, (std::array<uint32_t, 3>{37, 29, 19}));
  EXPECT_DOUBLE_EQ(part.origin[0], p.origin[0] + 5 * p.voxel_size);
  for (uint32_t z = 0; z < 19; ++z)
    for (uint32_t y = 0; y < 29; ++y)
      for (uint32_t x = 0; x < 37; ++x)
        ASSERT_EQ(part.density[part.index(x, y, z)], a.density[a.index(x + 5, y + 13, z + 21)]);
  // Detail channels too: whether a brick is near cloud is decided on whole bricks and a halo.
  for (int c = 0; c < 3; ++c) {
    if (a.detail[c].empty()) continue;
    for (uint32_t z = 0; z < 19; ++z)
      for (uint32_t y = 0; y < 29; ++y)
        for (uint32_t x = 0; x < 37; ++x)
          ASSERT_EQ(part.detail[c][part.index(x, y, z)], a.detail[c][a.index(x + 5, y + 13, z + 21)]) << "channel " << c;
  }
  GenerateOptions bad;
  bad.region_origin = {60, 0, 0};
  bad.region_extent = {10, 0, 0};
  EXPECT_THROW(generate(p, bad), InputError);
}

TEST(Pipeline, FinalVolumeTilesInXAndZ) {
  // The seam between the last and first voxel must look like any other neighbour pair: the mean
  // absolute difference across the seam stays within 1.6x of the interior mean (a volume that did
  // not wrap shows several times the interior difference there).
  Preset p = preset("cumulus");
  Volume v = generate(p);
  auto seam_ratio = [&](int axis) {
    double seam = 0, inner = 0;
    size_t ns = 0, ni = 0;
    const uint32_t n = v.dims[axis];
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x) {
          uint32_t c[3] = {x, y, z};
          uint32_t q[3] = {x, y, z};
          q[axis] = (c[axis] + 1) % n;
          double d = std::fabs(v.density[v.index(x, y, z)] - v.density[v.index(q[0], q[1], q[2])]);
          if (c[axis] == n - 1) seam += d, ++ns;
          else inner += d, ++ni;
        }
    return (seam / ns) / (inner / ni);
  };
  EXPECT_LT(seam_ratio(0), 1.6);
  EXPECT_LT(seam_ratio(2), 1.6);
  EXPECT_TRUE(v.tiles_xz);
}

// The exact form of the test above. A tiling volume is one tile of a periodic field, so at its
// seams (the first and last voxel in x and in z) every factor of the density that varies in x or z
// continues into the neighbouring tile bit for bit, and the baked seam voxels are that field's
// values, bit for bit:
//  - each channel's noise and the coverage noise, at the bake's lattice positions (voxel i of N at
//    i * P / N; exact in double at this resolution), equals itself one period on from the first
//    voxel (voxel N, the next tile's first) and one period back from the last (voxel -1);
//  - no tower's copy in the neighbouring tile reaches a seam voxel, so the towers the bake adds
//    once each are the periodic sum of their copies (a tower cut by the box would end in a step);
//  - the baked density of every seam voxel is the bake's formula applied to the grid noise (the
//    library's samples of one tile, which its Tiling tests tie to the point function), the height
//    profile, the towers and the coverage map: nothing at the edges (a fade, a brick artefact) departs from
//    the periodic field. The detail channels next to cloud across the seam are checked exactly by
//    DetailIsExactWithinOneVoxelOfCloud.
TEST(Pipeline, TilingVolumeContinuesExactlyAcrossItsSeams) {
  Preset p = preset("cumulus");
  rescale(p, 32);
  ASSERT_TRUE(p.tiling && p.coverage_enabled && p.tower_count > 0);
  const Volume v = generate(p);
  ASSERT_TRUE(v.tiles_xz);
  const auto N = v.dims;
  auto on_seam = [&](uint32_t x, uint32_t z) { return x == 0 || x == N[0] - 1 || z == 0 || z == N[2] - 1; };

  // The noise one period on / back across each seam the voxel lies on, against the noise here.
  size_t continued = 0;
  auto continues = [&](const noise3d::FractalParams& f, uint32_t x, uint32_t y, uint32_t z, const char* what) {
    const double P[3] = {double(f.period.x), double(f.period.y), double(f.period.z)};
    const uint32_t q[3] = {x, y, z};
    double at[3];
    for (int a = 0; a < 3; ++a) at[a] = double(q[a]) * P[a] / N[a];
    const double here = noise3d::evaluate(f, at[0], at[1], at[2]);
    for (int a : {0, 2}) {
      if (q[a] != 0 && q[a] != N[a] - 1) continue;
      double s[3] = {at[0], at[1], at[2]};
      s[a] += q[a] == 0 ? P[a] : -P[a];
      const double there = noise3d::evaluate(f, s[0], s[1], s[2]);
      ASSERT_EQ(std::memcmp(&there, &here, sizeof here), 0)
          << what << " at voxel (" << x << ", " << y << ", " << z << ") across the " << (a ? "z" : "x")
          << " seam: " << there << " vs " << here;
      ++continued;
    }
  };
  for (uint32_t z = 0; z < N[2]; ++z)
    for (uint32_t x = 0; x < N[0]; ++x) {
      if (!on_seam(x, z)) continue;
      continues(coverage_params(p), x, 0, z, "coverage");
      for (uint32_t y = 0; y < N[1]; ++y)
        for (int c = 0; c < 4; ++c)
          if (c == 0 || p.channels[c].enabled) continues(channel_params(p, c), x, y, z, "channel");
    }
  EXPECT_EQ(continued, size_t(2 * (N[0] + N[2])) * (1 + 4 * N[1]));  // corners lie on both seams

  // Towers are not periodic functions: the bake adds each one once. That is the periodic field
  // only if no tower's copy in a neighbouring tile (centre one tile width away) reaches a voxel of
  // this one: at the seam voxels, where it would come closest, its q must be >= 9 (the truncation).
  const std::vector<Tower> towers = resolve_towers(p);
  ASSERT_FALSE(towers.empty());
  for (const Tower& w : towers)
    for (int a : {0, 2})
      for (uint32_t i : {0u, N[a] - 1}) {
        const double u = (i + 0.5) / N[a], copy = w.center[a] + (i == 0 ? -1.0 : 1.0);
        EXPECT_GE((u - copy) * (u - copy) / (w.sigma[a] * w.sigma[a]), 9.0)
            << "the copy of a tower one tile away reaches voxel " << i << " of axis " << a;
      }
  // The bake's tower term at a voxel (generate.cpp's Shape: q summed over x, y, z, truncated at 9).
  auto tower_term = [&](uint32_t x, uint32_t y, uint32_t z) {
    const uint32_t q3[3] = {x, y, z};
    const double g3 = std::exp(-4.5);
    double add = 0;
    for (const Tower& w : towers) {
      double q = 0;
      for (int a = 0; a < 3; ++a) {
        const double u = (q3[a] + 0.5) / N[a];
        q += (u - w.center[a]) * (u - w.center[a]) / (w.sigma[a] * w.sigma[a]);
      }
      if (q < 9) add += w.amplitude * (std::exp(-0.5 * q) - g3) / (1 - g3);
    }
    return add;
  };

  const std::vector<float> cov = coverage_map(p);
  std::vector<float> r(v.voxel_count());
  noise3d::GridRegion g;
  g.size = N;
  noise3d::evaluate_grid(channel_params(p, 0), g, r.data());
  const float t = float(p.threshold), inv = float(1.0 / (1.0 - p.threshold)), scale = float(p.density_scale);
  size_t cloudy = 0, seam_voxels = 0, towered = 0;
  for (uint32_t z = 0; z < N[2]; ++z)
    for (uint32_t y = 0; y < N[1]; ++y)
      for (uint32_t x = 0; x < N[0]; ++x) {
        if (!on_seam(x, z)) continue;
        const size_t i = v.index(x, y, z);
        float shape = float(height_profile(p, (y + 0.5) / N[1]));
        shape += float(tower_term(x, y, z));
        shape *= cov[size_t(z) * N[0] + x];
        towered += tower_term(x, y, z) > 0;
        const float d = channel_value(p.channels[0], r[i]) * shape;
        const float want = std::clamp((d - t) * inv * scale, 0.0f, 1.0f);
        ASSERT_EQ(v.density[i], want) << "seam voxel (" << x << ", " << y << ", " << z << ")";
        cloudy += want > 0;
        ++seam_voxels;
      }
  std::printf("  cumulus at %ux%ux%u: %zu noise continuations bit-equal; of %zu seam voxels %zu hold cloud, %zu a tower\n",
              N[0], N[1], N[2], continued, seam_voxels, cloudy, towered);
  EXPECT_GT(cloudy, 0u) << "the seams must hold cloud for the reconstruction to mean something";
}

TEST(Pipeline, TowersVanishAtTheTileEdges) {
  Preset p = parse_preset(R"({"resolution": [48, 48, 48], "towers": {"count": 6, "seed": 3}})", "t.json");
  for (const Tower& t : resolve_towers(p))
    for (int a : {0, 2}) {
      EXPECT_GE(t.center[a] - 3 * t.sigma[a], 0.0);
      EXPECT_LE(t.center[a] + 3 * t.sigma[a], 1.0);
    }
}

TEST(Pipeline, HeightDistributionIsTheThesisFunction) {
  Preset p = preset("thesis");
  p.height_normalize = false;
  for (double h : {0.0, 0.01, 0.1, 0.5, 1.0})
    EXPECT_NEAR(height_profile(p, h), (1 - std::exp(-50 * h)) * std::exp(-4 * h), 1e-12);
  p.height_normalize = true;
  const double hs = std::log(1 + 50.0 / 4) / 50;
  EXPECT_NEAR(height_profile(p, hs), 1.0, 1e-12);
  EXPECT_LT(height_profile(p, hs + 0.01), 1.0);
  EXPECT_LT(height_profile(p, hs - 0.01), 1.0);
}

TEST(Pipeline, OccupancyIsConservative) {
  for (const char* name : {"thesis", "cumulus-field"}) {
    Preset p = preset(name);
    rescale(p, std::string(name) == "thesis" ? 80 : 256);
    Volume v = generate(p);
    const uint32_t c = v.occupancy_cell;
    const int pad = int(v.occupancy_padding);
    auto occ = [&](int x, int y, int z) {
      const auto& d = v.occupancy_dims;
      if (v.tiles_xz) x = (x % int(d[0]) + int(d[0])) % int(d[0]), z = (z % int(d[2]) + int(d[2])) % int(d[2]);
      if (x < 0 || y < 0 || z < 0 || x >= int(d[0]) || y >= int(d[1]) || z >= int(d[2])) return true;
      return v.occupancy[(size_t(z) * d[1] + y) * d[0] + x] != 0;
    };
    size_t checked = 0, occupied = 0;
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x) {
          if (v.density[v.index(x, y, z)] <= 0) continue;
          ++checked;
          for (int dz = -pad; dz <= pad; ++dz)
            for (int dy = -pad; dy <= pad; ++dy)
              for (int dx = -pad; dx <= pad; ++dx)
                ASSERT_TRUE(occ(int(x / c) + dx, int(y / c) + dy, int(z / c) + dz)) << name;
        }
    for (uint8_t o : v.occupancy) occupied += o;
    EXPECT_GT(checked, 0u);
    if (std::string(name) == "cumulus-field") {
      // Double padding dilates by 2 cells (16 voxels) each way, so at 256 voxels wide most of this
      // field's columns are reached; still a good share must be empty for skipping to pay.
      std::printf("  %s: %zu of %zu occupancy cells occupied\n", name, occupied, v.occupancy.size());
      EXPECT_LT(occupied, v.occupancy.size() * 8 / 10) << "a sparse field must leave cells empty to skip";
    }
  }
}

TEST(Pipeline, OccupancyDilationEqualsTheNeighbourhoodRule) {
  // dilate_occupancy against the rule written out cell by cell: each axis in turn, a cell takes
  // the first non-zero value of its neighbours d = -p .. p (wrapping in x and z when tiling), on
  // grids with odd sizes, values other than 0/1, and paddings beyond the grid.
  uint32_t h = 12345;
  auto next = [&] { return (h = h * 1664525u + 1013904223u) >> 8; };
  for (int trial = 0; trial < 24; ++trial) {
    const std::array<uint32_t, 3> od{1 + next() % 9, 1 + next() % 7, 1 + next() % 8};
    const uint32_t pad = next() % 4;
    const bool tiles = trial % 2 == 1;
    std::vector<uint8_t> grid(static_cast<size_t>(od[0]) * od[1] * od[2]);
    for (uint8_t& g : grid) g = next() % 7 == 0 ? uint8_t(1 + next() % 3) : 0;
    std::vector<uint8_t> want = grid;
    for (int a = 0; a < 3; ++a) {
      std::vector<uint8_t> next_grid(want.size());
      const int n = int(od[a]);
      for (uint32_t z = 0; z < od[2]; ++z)
        for (uint32_t y = 0; y < od[1]; ++y)
          for (uint32_t x = 0; x < od[0]; ++x) {
            int p[3] = {int(x), int(y), int(z)};
            const int c = p[a];
            uint8_t on = 0;
            for (int d = -int(pad); d <= int(pad) && !on; ++d) {
              int q = c + d;
              if (tiles && a != 1) q = ((q % n) + n) % n;
              else if (q < 0 || q >= n) continue;
              p[a] = q;
              on = want[(size_t(p[2]) * od[1] + p[1]) * od[0] + p[0]];
            }
            next_grid[(size_t(z) * od[1] + y) * od[0] + x] = on;
          }
      want.swap(next_grid);
    }
    dilate_occupancy(grid, od, pad, tiles);
    EXPECT_EQ(grid, want) << "trial " << trial << ": " << od[0] << "x" << od[1] << "x" << od[2] << " pad " << pad;
  }
}

TEST(Pipeline, GoldenChecksumOfTheTinyPreset) {
  // FNV-1a of the tiny preset's density bytes: any change to noise, pipeline or defaults shows up.
  Volume v = generate(preset("tiny"));
  uint64_t h = 1469598103934665603ull;
  const auto* b = reinterpret_cast<const uint8_t*>(v.density.data());
  for (size_t i = 0; i < v.density.size() * 4; ++i) h = (h ^ b[i]) * 1099511628211ull;
  EXPECT_EQ(h, 0x2a69792f43c25e4eull) << std::hex << h;
}

// ---------------------------------------------------------------------------------------------
TEST(Export, VdbRoundTripFloatAndHalf) {
  TempDir dir;
  Volume v = generate(preset("tiny"));
  for (bool half : {false, true}) {
    ExportOptions o;
    o.vdb_half = half;
    o.vdb_bake_erosion = false;  // the detail grid too
    const std::string path = dir / (half ? "h.vdb" : "f.vdb");
    write_vdb(v, path, o);
    Volume r = read_vdb(path);
    // The reader crops to the active bounding box; tiny's cloud touches every side but the top.
    ASSERT_LE(r.dims[1], v.dims[1]);
    const uint32_t oy = uint32_t(std::lround((r.origin[1] - v.origin[1]) / v.voxel_size));
    EXPECT_DOUBLE_EQ(r.voxel_size, v.voxel_size);
    double maxerr = 0;
    for (uint32_t z = 0; z < r.dims[2]; ++z)
      for (uint32_t y = 0; y < r.dims[1]; ++y)
        for (uint32_t x = 0; x < r.dims[0]; ++x)
          maxerr = std::max(maxerr, double(std::fabs(r.density[r.index(x, y, z)] - v.density[v.index(x, y + oy, z)])));
    if (half) EXPECT_LE(maxerr, 1.0 / 2048) << "half keeps 11 significant bits";
    else EXPECT_EQ(maxerr, 0.0);
    std::string info = describe_vdb(path);
    EXPECT_NE(info.find("grid \"density\": float, class fog volume"), std::string::npos) << info;
    EXPECT_NE(info.find("grid \"detail_g\""), std::string::npos) << info;
    EXPECT_EQ(info.find("Houdini"), std::string::npos);
    EXPECT_NE(info.find("saved as " + std::string(half ? "half" : "float")), std::string::npos) << info;
  }
}

// Levels of detail (export.vdb.lod): grids NAME_level_L, voxels 2^L times as large, placed over the
// fine grid in world space, and mean-preserving: every channel's integral (sum of values times the
// voxel volume) equals the fine grid's within 0.1% at every level, in normalized and physical units.
TEST(Export, LodLevelsDoubleTheVoxelAndKeepEveryChannelsIntegral) {
  TempDir dir;
  for (const char* name : {"tiny", "cumulus-field"}) {
    Preset p = preset(name);
    if (std::string(name) == "cumulus-field") rescale(p, 64);
    const Volume v = generate(p);
    for (bool physical : {false, true}) {
      SCOPED_TRACE(std::string(name) + (physical ? " physical" : " normalized"));
      ExportOptions o;
      o.vdb_lod = 3;
      o.vdb_physical = physical;
      o.vdb_bake_erosion = false;  // the detail grids, and their levels, too
      const std::string path = dir / "lod.vdb";
      write_vdb(v, path, o);
      EXPECT_EQ(vdb_lod_levels(path), 3u);
      const Volume fine = read_vdb(path);
      auto integral = [](const Volume& w, const std::vector<float>& c) {
        double s = 0;
        for (float x : c) s += x;
        return s * w.voxel_size * w.voxel_size * w.voxel_size;
      };
      auto centre = [](const Volume& w, int a) { return w.origin[a] + 0.5 * w.dims[a] * w.voxel_size; };
      for (uint32_t l = 1; l <= 3; ++l) {
        const Volume c = read_vdb_level(path, l);
        EXPECT_DOUBLE_EQ(c.voxel_size, v.voxel_size * double(1u << l)) << "level " << l;
        const double f = integral(fine, fine.density), g = integral(c, c.density);
        ASSERT_GT(f, 0);
        EXPECT_NEAR(g / f, 1.0, 1e-3) << "level " << l << ": density integral " << g << " against " << f;
        for (int d = 0; d < 3; ++d) {
          if (!fine.detail[d].empty()) {
            EXPECT_EQ(c.detail[d].size(), c.density.size()) << v.detail_names[d];
          }
        }
        // Overlaid in world space: the level's box holds the fine box, at most a coarse voxel wider a side.
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(c.origin[a], fine.origin[a] + 1e-6) << "axis " << a << " level " << l;
          EXPECT_NEAR(centre(c, a), centre(fine, a), c.voxel_size) << "axis " << a << " level " << l;
        }
      }
      // Every channel's grids as stored (the reader crops the detail grids, which reach a voxel past
      // the density, to the density's box): the same integral at every level.
      std::map<std::string, double> integral0;
      size_t levels = 0;
      for (const VdbGridSummary& g : vdb_grid_summaries(path)) {
        const size_t at = g.name.find("_level_");
        if (at == std::string::npos) {
          integral0[g.name] = g.integral;
          continue;
        }
        ++levels;
        const uint32_t l = uint32_t(std::stoul(g.name.substr(at + 7)));
        const double f = integral0.at(g.name.substr(0, at));
        EXPECT_DOUBLE_EQ(g.voxel_size, v.voxel_size * double(1u << l)) << g.name;
        EXPECT_NEAR(g.integral / f, 1.0, 1e-3) << g.name << ": " << g.integral << " against " << f;
      }
      EXPECT_EQ(levels, 3 * integral0.size()) << "every channel has its levels";
      EXPECT_GE(integral0.size(), 2u) << "density and at least one detail channel";
      const std::string info = describe_vdb(path);
      EXPECT_NE(info.find("file lod_levels: 3"), std::string::npos) << info;
      EXPECT_NE(info.find("levels of detail: 3 (density_level_1 .. density_level_3"), std::string::npos) << info;
      for (const char* g : {"density_level_1", "density_level_3", "detail_g_level_2"})
        EXPECT_NE(info.find("grid \"" + std::string(g) + "\""), std::string::npos) << g << "\n" << info;
      try {
        read_vdb_level(path, 4);
        ADD_FAILURE() << "level 4 of a file with 3";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("the file has levels 0 .. 3"), std::string::npos) << e.what();
      }
    }
  }
}

// KTX2 header fields a loader checks (every texel format's values: TextureRoundTrip in
// test_robustness.cpp).
TEST(Export, Ktx2HeaderHoldsWhatLoadersCheck) {
  TempDir dir;
  Volume v = generate(preset("tiny"));
  ExportOptions o;
  o.texel = parse_texel("rgba8");
  write_volume(v, dir / "rgba8.ktx2", Format::Ktx2, o);
  std::ifstream k(dir / "rgba8.ktx2", std::ios::binary);
  char hdr[48];
  k.read(hdr, 48);
  EXPECT_EQ(std::memcmp(hdr, "\xABKTX 20\xBB\r\n\x1A\n", 12), 0);
  uint32_t vk, depth;
  std::memcpy(&vk, hdr + 12, 4);
  std::memcpy(&depth, hdr + 28, 4);
  EXPECT_EQ(vk, 37u);  // VK_FORMAT_R8G8B8A8_UNORM
  EXPECT_EQ(depth, v.dims[2]);
}

TEST(Export, AtlasHasOneTilePerHeightLevel) {
  TempDir dir;
  Volume v = generate(preset("tiny"));
  write_atlas(v, dir / "a.png", Format::AtlasPng);
  write_atlas(v, dir / "a.exr", Format::AtlasExr);
  std::ifstream side(dir / "a.json");
  std::stringstream ss;
  ss << side.rdbuf();
  EXPECT_NE(ss.str().find("\"tiles\": [\n      6,\n      6\n    ]"), std::string::npos) << ss.str();  // 32 slices -> 6x6
  EXPECT_GT(fs::file_size(dir / "a.png"), 1000u);
  EXPECT_GT(fs::file_size(dir / "a.exr"), 1000u);
}

TEST(Export, FailedWriteLeavesNoFile) {
  TempDir dir;
  const std::string path = dir / "x.vdb";
  EXPECT_THROW(atomic_write(path, [](const std::string& tmp) {
                 std::ofstream(tmp) << "half";
                 throw IoError("simulated failure");
               }),
               IoError);
  EXPECT_TRUE(fs::is_empty(dir.path)) << "neither the output nor its temporary may remain";
}

TEST(Export, ReadersRejectBadInputsClearly) {
  TempDir dir;
  std::ofstream(dir / "junk.vdb") << "not a vdb";
  EXPECT_THROW(read_volume(dir / "junk.vdb"), InputError);
  EXPECT_THROW(read_volume(dir / "missing.vdb"), InputError);
  Volume v = generate(preset("tiny"));
  write_raw(v, dir / "t.raw", {});
  fs::resize_file(dir / "t.raw", 1000);
  try {
    read_volume(dir / "t.raw");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("holds 1000 bytes"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
TEST(Cli, GenerateWritesEveryOutputAndInfoDescribesThem) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_cli("generate tiny -q -o " + (dir / "t.vdb") + " -o " + (dir / "t.raw") + " -o " + (dir / "t.ktx2"), &out), 0) << out;
  for (const char* f : {"t.vdb", "t.raw", "t.json", "t.occupancy.raw", "t.ktx2"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  ASSERT_EQ(run_cli("info " + (dir / "t.vdb"), &out), 0) << out;
  EXPECT_NE(out.find("grid \"density\""), std::string::npos) << out;
  EXPECT_NE(out.find("preset: tiny"), std::string::npos) << out;
  ASSERT_EQ(run_cli("info " + (dir / "t.raw"), &out), 0) << out;
  EXPECT_NE(out.find("size 32 x 32 x 32"), std::string::npos) << out;
}

// A run whose outputs all bake the erosion (the default .vdb) computes the detail noise only in the
// detail blocks that hold cloud, and none when the erosion does not apply (one detail channel);
// the VDB equals, voxel for voxel, the one a run with a texture output beside it writes (which
// keeps the detail's trilinear reach), and --stats shows the smaller share of detail work.
TEST(Cli, BakedOnlyRunsComputeDetailWhereItIsReadAndWriteTheSameVdb) {
  TempDir dir;
  auto detail_bricks = [](const std::string& stats) {
    const size_t at = stats.find(" with detail)");
    EXPECT_NE(at, std::string::npos) << stats;
    size_t b = stats.rfind(' ', at - 1);
    return std::stoul(stats.substr(b + 1, at - b - 1));
  };
  for (const char* preset : {"thesis --resolution 64", "cumulus-field --resolution 128"}) {
    SCOPED_TRACE(preset);
    std::string baked, mixed;
    ASSERT_EQ(run_cli(std::string("generate ") + preset + " -q --stats -o " + (dir / "a.vdb"), &baked), 0) << baked;
    ASSERT_EQ(run_cli(std::string("generate ") + preset + " -q --stats -o " + (dir / "b.vdb") + " -o " + (dir / "b.raw"),
                      &mixed),
              0)
        << mixed;
    const Volume a = read_vdb(dir / "a.vdb"), b = read_vdb(dir / "b.vdb");
    EXPECT_EQ(a.dims, b.dims);
    EXPECT_TRUE(same_bytes(a.density, b.density));
    EXPECT_LT(detail_bricks(baked), detail_bricks(mixed)) << baked << "\n" << mixed;
  }
}

TEST(Cli, ErrorsExitNonZeroWithTheirMessage) {
  TempDir dir;
  std::string out;
  EXPECT_EQ(run_cli("generate tiny -o " + (dir / "t.xyz"), &out), 1);
  EXPECT_NE(out.find("cannot tell the format"), std::string::npos) << out;
  EXPECT_EQ(run_cli("generate cumulus-field --max-memory 10M -o " + (dir / "f.vdb"), &out), 1);
  EXPECT_NE(out.find("more than --max-memory"), std::string::npos) << out;
  EXPECT_EQ(run_cli("generate tiny --set threshold=3 -o " + (dir / "t.vdb"), &out), 1);
  EXPECT_NE(out.find("/threshold: 3 is out of range"), std::string::npos) << out;
  EXPECT_EQ(run_cli("validate " + kPresets + "tiny.json " + kPresets + "thesis.json", &out), 0) << out;
  std::ofstream(dir / "bad.json") << "{\"seed\": -1}";
  EXPECT_EQ(run_cli("validate " + (dir / "bad.json"), &out), 1);
  EXPECT_NE(out.find("/seed: -1 is out of range"), std::string::npos) << out;
  EXPECT_TRUE(fs::is_empty(dir.path) || !fs::exists(dir / "t.vdb"));
}

// --lod N and export.vdb.lod: levels in the file and its info; a count outside 0 .. 16 (the table's
// range) or beyond one voxel along the longest axis (tiny, 32^3: 5) is refused by name, value and
// range, exit 1, nothing written; 0 is the default (no levels, and the file without the metadata).
// Issue 46 item 3: --voxel-budget chooses the voxel size (world size kept) from the active fraction
// of a sample and the skipping bound. On tiny and cumulus (a quarter of its size, for time) at two
// budgets each: the generated volume's active voxels fit the budget and use at least 85% of it
// (measured 94-97%), the world extent stays the preset's within a voxel, and the skipping bound
// is a ceiling of the true count.
TEST(VoxelBudget, ChosenSizeFitsTheBudgetAndUsesMostOfIt) {
  for (const char* name : {"tiny", "cumulus"})
    for (uint64_t budget : {uint64_t(30000), uint64_t(120000)}) {
      Preset p = preset(name);
      if (std::string(name) == "cumulus") rescale(p, 64);
      const double extent = p.resolution[0] * p.voxel_size;
      const BudgetChoice c = choose_for_budget(p, budget, 2);
      Preset q = p;
      rescale(q, c.longest);
      ASSERT_EQ(q.resolution, c.resolution);
      EXPECT_NEAR(c.resolution[0] * c.voxel_size, extent, c.voxel_size) << name;
      GenerateOptions go;
      go.threads = 2;
      go.detail = false;
      GenerateStats st;
      generate(q, go, &st);
      std::cout << name << " budget " << budget << ": " << describe(c) << "; generated " << st.active_voxels << "\n";
      EXPECT_LE(st.active_voxels, budget) << name;
      EXPECT_GE(double(st.active_voxels), 0.85 * double(budget)) << name;
      EXPECT_GE(c.bound, st.active_voxels) << name;
      EXPECT_LE(c.estimate, budget) << name;
    }
}

TEST(VoxelBudget, TheCliPrintsTheSizeStoresTheBudgetAndRefusesBadInput) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_cli("generate tiny --voxel-budget 50K -o " + (dir / "a.vdb"), &out), 0) << out;
  EXPECT_NE(out.find("voxel budget 50000: voxel size "), std::string::npos) << out;
  ASSERT_EQ(run_cli("info " + (dir / "a.vdb"), &out), 0) << out;
  EXPECT_NE(out.find("voxel_budget: 50000"), std::string::npos) << out;
  for (const char* bad : {"12X", "-5M", "nan", "0.001K", ""}) {
    EXPECT_EQ(run_cli(std::string("generate tiny -q --voxel-budget '") + bad + "' -o " + (dir / "b.vdb"), &out), 1) << bad;
    EXPECT_NE(out.find("--voxel-budget"), std::string::npos) << bad << ": " << out;
  }
  EXPECT_EQ(run_cli("generate tiny -q --voxel-budget 1M --resolution 64 -o " + (dir / "b.vdb"), &out), 1) << out;
  EXPECT_NE(out.find("give one of them"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "b.vdb"));
}

TEST(Cli, LodWritesNamedLevelsAndRefusesBadCounts) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_cli("generate tiny -q --lod 2 -o " + (dir / "a.vdb"), &out), 0) << out;
  ASSERT_EQ(run_cli("info " + (dir / "a.vdb"), &out), 0) << out;
  EXPECT_NE(out.find("levels of detail: 2 (density_level_1 .. density_level_2; voxel size 25, 50, 100)"),
            std::string::npos)
      << out;
  ASSERT_EQ(run_cli("generate tiny -q --set export.vdb.lod=5 -o " + (dir / "b.vdb"), &out), 0) << out;
  EXPECT_EQ(vdb_lod_levels(dir / "b.vdb"), 5u);
  ASSERT_EQ(run_cli("generate tiny -q --lod 0 -o " + (dir / "c.vdb"), &out), 0) << out;
  EXPECT_EQ(vdb_lod_levels(dir / "c.vdb"), 0u);
  ASSERT_EQ(run_cli("info " + (dir / "c.vdb"), &out), 0) << out;
  EXPECT_EQ(out.find("lod"), std::string::npos) << out;
  const size_t files = testutil::list_dir(dir.path).size();
  const std::pair<const char*, const char*> bad[] = {
      {"--lod 40", "/export/vdb/lod: 40 is out of range; allowed: integer in [0, 16]"},
      {"--lod -1", "/export/vdb/lod: -1 is out of range"},
      {"--lod two", "/export/vdb/lod"},
      {"--lod 6", "export.vdb.lod (--lod): 6 is more levels than a 32x32x32 volume has; allowed: 0 .. 5"},
      {"--set export.vdb.lod=9 --resolution 64", "allowed: 0 .. 6"},
  };
  for (const auto& [args, message] : bad) {
    EXPECT_EQ(run_cli("generate tiny -q " + std::string(args) + " -o " + (dir / "d.vdb"), &out), 1) << args << "\n" << out;
    EXPECT_NE(out.find(message), std::string::npos) << args << "\n" << out;
  }
  EXPECT_EQ(testutil::list_dir(dir.path).size(), files) << "a refused run writes nothing";
}

// Interrupted at known points (test hook CLOUDGEN_TEST_HOLD, a handshake, no sleeping): a run of
// several outputs during generation and with every output staged but none published, and a frame
// sequence with its first frame staged and with every frame staged. Either way nothing appears,
// the file that was there stays byte for byte, no temporaries are left, and the message says so.
struct InterruptCase {
  const char* name;
  const char* hold;  ///< CLOUDGEN_TEST_HOLD: where the run stops until signalled
  std::vector<std::string> args;  ///< "DIR/" stands for the test's folder
  const char* existing;           ///< a file there before the run, which must survive
};
const InterruptCase kInterruptCases[] = {
    {"GenerateDuringGeneration", "generate",
     {"generate", "cumulus-field", "--resolution", "64", "-q", "-o", "DIR/field.vdb", "-o", "DIR/field.raw", "-o",
      "DIR/old.vdb"},
     "old.vdb"},
    {"GenerateWithEveryOutputStaged", "commit",
     {"generate", "cumulus-field", "--resolution", "64", "-q", "-o", "DIR/field.vdb", "-o", "DIR/field.raw", "-o",
      "DIR/old.vdb"},
     "old.vdb"},
    {"SequenceWithTheFirstFrameStaged", "frames", {"generate", "tiny", "-q", "--frames", "0:3", "-o", "DIR/c_####.vdb"},
     "c_0001.vdb"},
    {"SequenceWithEveryFrameStaged", "commit", {"generate", "tiny", "-q", "--frames", "0:3", "-o", "DIR/c_####.vdb"},
     "c_0001.vdb"},
};
class Interrupted : public ::testing::TestWithParam<InterruptCase> {};
TEST_P(Interrupted, RunLeavesNoPartialOutput) {
  const InterruptCase& c = GetParam();
  TempDir dir;
  testutil::write_text(dir / c.existing, "previous contents");
  testutil::Process p;
  for (std::string a : c.args) p.args.push_back(a.rfind("DIR/", 0) == 0 ? dir / a.substr(4) : a);
  p.env = {std::string("CLOUDGEN_TEST_HOLD=") + c.hold};
  p.signal_on = std::string("test hold at ") + c.hold;
  const auto r = p.run();
  ASSERT_TRUE(r.signalled) << r.out;
  EXPECT_EQ(r.code, 130) << r.out;
  EXPECT_NE(r.out.find("no output was written or replaced"), std::string::npos) << r.out;
  EXPECT_EQ(testutil::list_dir(dir.path), std::vector<std::string>{c.existing})
      << "an interrupted run must leave neither outputs nor temporaries";
  EXPECT_EQ(testutil::read_text(dir / c.existing), "previous contents");
}
INSTANTIATE_TEST_SUITE_P(EveryHoldPoint, Interrupted, ::testing::ValuesIn(kInterruptCases),
                         [](const ::testing::TestParamInfo<InterruptCase>& i) { return std::string(i.param.name); });

TEST(Cli, NoiseCubeIsOneTileAndReferenceModeMatchesPerlin) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_cli("noise --kind worley --period 3 --octaves 2 --seed 5 --size 24 --threads 1 -o " + (dir / "a.raw"), &out), 0) << out;
  ASSERT_EQ(run_cli("noise --kind worley --period 3 --octaves 2 --seed 5 --size 24 --threads 2 -o " + (dir / "b.raw"), &out), 0) << out;
  std::ifstream a(dir / "a.raw", std::ios::binary), b(dir / "b.raw", std::ios::binary);
  std::vector<float> va(24 * 24 * 24), vb(va.size());
  a.read(reinterpret_cast<char*>(va.data()), va.size() * 4);
  b.read(reinterpret_cast<char*>(vb.data()), vb.size() * 4);
  EXPECT_TRUE(same_bytes(va, vb));
  noise3d::FractalParams p;
  p.kind = noise3d::Kind::Worley, p.period = noise3d::Period::cube(3), p.octaves = 2, p.seed = 5;
  EXPECT_NEAR(va[(7 * 24 + 5) * 24 + 11], noise3d::evaluate(p, 11 * 3.0 / 24, 5 * 3.0 / 24, 7 * 3.0 / 24), 1e-6);
  std::ifstream side(dir / "a.json");
  std::stringstream ss;
  ss << side.rdbuf();
  EXPECT_NE(ss.str().find("\"kind\": \"worley\""), std::string::npos);
  EXPECT_NE(ss.str().find("\"min\""), std::string::npos);
  ASSERT_EQ(run_cli("noise --kind perlin --reference --at 3.14,42,7", &out), 0);
  EXPECT_EQ(out, "0.13691995878400012\n");
  EXPECT_EQ(run_cli("noise --kind perlin --lacunarity 2.5 --size 8 -o " + (dir / "c.raw"), &out), 1);
  EXPECT_NE(out.find("lacunarity"), std::string::npos) << out;
}

// `cloudgen noise` declares its flags in one table (cloudgen/schema.h) and checks them with the
// preset reader's checker: each bad value is refused naming the flag, the value and the allowed
// range, every bad flag at once, and --help shows the same ranges and defaults.
TEST(Cli, NoiseFlagsAreCheckedAgainstTheirTable) {
  TempDir dir;
  const std::string out = dir / "n.raw";
  std::string text;
  struct Case {
    std::string args;
    std::vector<const char*> named;
  } cases[] = {
      {"--octaves 40", {"--octaves: 40 is out of range; allowed: integer in [1, 16]"}},
      {"--octaves abc", {"--octaves: \"abc\" has the wrong type; expected an integer in [1, 16]"}},
      {"--kind foo --gain 0 --size 0",
       {"--kind: \"foo\" is not allowed; expected one of: perlin | worley | perlin-worley",
        "--gain: 0 is out of range; allowed: number in [1e-06, 1]", "--size: 0 is out of range; allowed: integer in [1, 2048]"}},
      {"--lacunarity 2.5", {"--lacunarity: 2.5 has the wrong type; expected an integer in [2, 16]"}},
      {"--period 0", {"--period: 0 is out of range; allowed: integer in [1, 1073741824]"}},
      {"--period 4,4,2.5", {"--period/2: 2.5 has the wrong type; expected an integer in [1, 1073741824]"}},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(run_cli("noise " + c.args + " -o " + out, &text), 1) << c.args << "\n" << text;
    for (const char* n : c.named) EXPECT_NE(text.find(n), std::string::npos) << c.args << "\n" << text << "\nlacks: " << n;
  }
  EXPECT_FALSE(fs::exists(out));
  ASSERT_EQ(run_cli("noise --help", &text), 0);
  for (const char* n : {"fBm octaves: integer in [1, 16] (default 1)", "perlin | worley | perlin-worley (default perlin)",
                        "integer in [1, 2048] (default 64)", "integer in [0, 2^64 - 1] (default 0)"})
    EXPECT_NE(text.find(n), std::string::npos) << n << "\n" << text;
  ASSERT_EQ(run_cli("noise --period 4,4,5 --size 8 -o " + out, &text), 0) << text;
  EXPECT_NE(read_text(dir / "n.json").find("\"period\": [\n      4,\n      4,\n      5\n    ]"), std::string::npos)
      << read_text(dir / "n.json");
}
