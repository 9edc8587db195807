// Baked motion sequences (cloudgen/sequence.h, `cloudgen generate --frames`): each frame against a
// reference computed here from motion_displacement and the static voxels, velocity against the
// time derivative, t = 0 and still motion against the static grid, the loop rule, CLI errors and
// determinism across thread counts.
#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudgen/scale.h"
#include "cloudgen/sequence.h"
#include "test_util.h"

using namespace cloudgen;
using testutil::kPresets;
using testutil::run_cli;
using testutil::same_bytes;
using testutil::TempDir;

namespace {

Volume tiny(bool tiling, uint32_t resolution = 32) {
  Preset p = load_preset(kPresets + "tiny.json", {std::string("tiling=") + (tiling ? "true" : "false")});
  rescale(p, resolution);
  return generate(p);
}

/// The viewer's texture read, written out independently of the bake: zero outside the box
/// (always in y, in x/z unless the volume tiles), else trilinear with x/z wrapped (tiling) or
/// indices clamped (box), voxel centres at origin + (i + 0.5) * voxel_size.
double reference(const Volume& v, const std::vector<float>& ch, glm::dvec3 q) {
  double u[3];
  int64_t n[3] = {v.dims[0], v.dims[1], v.dims[2]};
  for (int a = 0; a < 3; ++a) {
    const double uvw = (q[a] - v.origin[a]) / (n[a] * v.voxel_size);
    const bool wraps = v.tiles_xz && a != 1;
    if (!wraps && (uvw < 0 || uvw > 1)) return 0;
    u[a] = uvw * n[a] - 0.5;
  }
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    int64_t idx[3];
    double w = 1;
    for (int a = 0; a < 3; ++a) {
      const double fl = std::floor(u[a]);
      const int64_t o = (c >> a) & 1;
      int64_t i = int64_t(fl) + o;
      if (v.tiles_xz && a != 1) i = ((i % n[a]) + n[a]) % n[a];
      else i = std::clamp<int64_t>(i, 0, n[a] - 1);
      idx[a] = i;
      w *= o ? u[a] - fl : 1 - (u[a] - fl);
    }
    acc += w * ch[v.index(uint32_t(idx[0]), uint32_t(idx[1]), uint32_t(idx[2]))];
  }
  return acc;
}

/// Max |frame - reference| over the frame's voxels and a margin of 2 voxels around its box
/// (outside the box the frame is 0), plus the largest reference value found outside the box.
struct Compare {
  double max_err = 0, outside = 0;
};
Compare compare_frame(const Volume& stat, const MotionParams& m, const MotionFrame& f) {
  Compare c;
  const Volume& fv = f.volume;
  const double vs = stat.voxel_size;
  const double height = stat.dims[1] * vs;
  for (int64_t k = -2; k < int64_t(fv.dims[2]) + 2; ++k)
    for (int64_t j = -2; j < int64_t(fv.dims[1]) + 2; ++j)
      for (int64_t i = -2; i < int64_t(fv.dims[0]) + 2; ++i) {
        const glm::dvec3 p(fv.origin[0] + (i + 0.5) * vs, fv.origin[1] + (j + 0.5) * vs, fv.origin[2] + (k + 0.5) * vs);
        const double h = (p.y - stat.origin[1]) / height;
        const glm::dvec3 d = motion_displacement(m, f.time, h);
        const double want = reference(stat, stat.density, p - d);
        const bool in = i >= 0 && j >= 0 && k >= 0 && i < fv.dims[0] && j < fv.dims[1] && k < fv.dims[2];
        if (in) c.max_err = std::max(c.max_err, std::abs(double(fv.density[fv.index(uint32_t(i), uint32_t(j), uint32_t(k))]) - want));
        else if (!stat.tiles_xz) c.outside = std::max(c.outside, want);  // a tile repeats beyond its box
      }
  return c;
}

double rms_change(const Volume& a, const Volume& b) {
  EXPECT_EQ(a.dims, b.dims);
  double s = 0;
  for (size_t i = 0; i < a.density.size(); ++i) s += (double(a.density[i]) - b.density[i]) * (a.density[i] - b.density[i]);
  return std::sqrt(s / double(a.density.size()));
}

}  // namespace

// A frame equals the static grid sampled at p - D(h(p), t), within float rounding (1e-5 on
// densities in [0, 1]); for a box volume the frame's box holds every voxel the cloud reaches.
TEST(Sequence, FrameIsTheStaticVolumeAtDisplacedPositions) {
  for (bool tiling : {true, false}) {
    const Volume stat = tiny(tiling);
    MotionParams m;  // the defaults: wind 10 m/s with shear, flow map
    m.flow_speed = 0.05;  // a faster flow, so the phase moves noticeably in these times
    for (double t : {0.4, 7.0, 31.0}) {
      const MotionFrame f = bake_frame(stat, m, int64_t(std::lround(t * 10)), 10.0, 2);
      ASSERT_NEAR(f.time, t, 1e-12);
      const Compare c = compare_frame(stat, m, f);
      EXPECT_LT(c.max_err, 1e-5) << "tiling " << tiling << " t " << t;
      EXPECT_EQ(c.outside, 0.0) << "cloud outside the frame's box, tiling " << tiling << " t " << t;
      if (!tiling && t > 30) {  // 31 s of >= 10 m/s wind: the box has moved by more than 12 voxels
        EXPECT_GT(f.volume.origin[0], stat.origin[0] + 10 * stat.voxel_size);
      }
    }
  }
}

// velocity = dD/dt: against a central difference with a step a hundred times smaller (1e-6 s),
// within 1e-4 m/s, at every row; at flow phase 0 (t = 0), where the seed's blend weight has a kink,
// between the one-sided derivatives; at the base (h = 0, no flow) it is the wind itself.
TEST(Sequence, VelocityIsTheTimeDerivativeOfTheDisplacement) {
  const Volume stat = tiny(false);
  MotionParams m;
  m.flow_speed = 0.05;
  for (int64_t frame : {0, 37, 523}) {
    const MotionFrame f = bake_frame(stat, m, frame, 100.0, 1);
    ASSERT_EQ(f.row_velocity.size(), f.volume.dims[1]);
    for (uint32_t j = 0; j < f.volume.dims[1]; ++j) {
      const double y = f.volume.origin[1] + (j + 0.5) * stat.voxel_size;
      const double h = (y - stat.origin[1]) / (stat.dims[1] * stat.voxel_size);
      const double e = 1e-6;
      const glm::dvec3 fine = (motion_displacement(m, f.time + e, h) - motion_displacement(m, f.time - e, h)) / (2 * e);
      const glm::dvec3 ahead = (motion_displacement(m, f.time + e, h) - motion_displacement(m, f.time, h)) / e;
      const glm::dvec3 behind = (motion_displacement(m, f.time, h) - motion_displacement(m, f.time - e, h)) / e;
      for (int a = 0; a < 3; ++a) {
        if (frame == 0) {  // flow phase 0: a kink of the blend weight, where dD/dt jumps; any value
                           // between the one-sided derivatives will do (1e-3 m/s of slack)
          EXPECT_GE(f.row_velocity[j][a], std::min(ahead[a], behind[a]) - 1e-3) << "row " << j << " axis " << a;
          EXPECT_LE(f.row_velocity[j][a], std::max(ahead[a], behind[a]) + 1e-3) << "row " << j << " axis " << a;
        } else {
          EXPECT_NEAR(f.row_velocity[j][a], fine[a], 1e-4) << "frame " << frame << " row " << j << " axis " << a;
        }
      }
    }
    // The base moves with the wind: 10 m/s along 60 degrees (plus the flow, zero at h = 0).
    const glm::dvec3 base = motion_velocity(m, f.time, 0.0);
    EXPECT_NEAR(base.x, 10 * std::sin(M_PI / 3), 1e-6);
    EXPECT_NEAR(base.z, -10 * std::cos(M_PI / 3), 1e-6);
    EXPECT_NEAR(base.y, 0.0, 1e-9);
  }
}

// D(h, 0) = 0, so frame 0 is the static grid bit for bit, for the tileable and the box volume,
// in memory and through the written .vdb.
TEST(Sequence, FrameAtTimeZeroIsTheStaticGridExactly) {
  TempDir dir;
  for (bool tiling : {true, false}) {
    const Volume stat = tiny(tiling);
    const MotionFrame f = bake_frame(stat, MotionParams{}, 0, 24.0);
    EXPECT_EQ(f.volume.dims, stat.dims);
    EXPECT_EQ(f.volume.origin, stat.origin);
    EXPECT_TRUE(same_bytes(f.volume.density, stat.density));
    EXPECT_TRUE(same_bytes(f.volume.detail[0], stat.detail[0]));
    write_vdb(stat, dir / "static.vdb", {});
    OutputBatch batch;
    write_vdb_frame(f, dir / "frame.vdb", {}, batch);
    batch.commit();
    const Volume a = read_vdb(dir / "static.vdb"), b = read_vdb(dir / "frame.vdb");
    EXPECT_EQ(a.dims, b.dims);
    EXPECT_EQ(a.origin, b.origin);
    EXPECT_TRUE(same_bytes(a.density, b.density)) << "tiling " << tiling;
  }
}

// No wind and no flow (or a flow of zero amplitude): every frame is the static grid exactly.
TEST(Sequence, StillMotionGivesTheStaticGridEveryFrame) {
  const Volume stat = tiny(false);
  MotionParams still;
  still.wind_speed = 0;
  still.flow_speed = 0;
  MotionParams flat;  // the flow cycles, with no amplitude
  flat.wind_speed = 0;
  flat.flow_up = flat.flow_forward = 0;
  EXPECT_FALSE(motion_moves(still));
  for (const MotionParams& m : {still, flat})
    for (int64_t frame : {1, 2, 50, 1000}) {
      const MotionFrame f = bake_frame(stat, m, frame, 24.0);
      EXPECT_EQ(f.volume.dims, stat.dims);
      EXPECT_TRUE(same_bytes(f.volume.density, stat.density)) << "frame " << frame;
      for (const glm::dvec3& v : f.row_velocity) EXPECT_EQ(glm::length(v), 0.0);
    }
}

// --loop: frame B + 1 (computed) equals frame A within 1e-4, and the change across the wrap is no
// larger than 1.05 times the largest change between other consecutive frames. Without --loop the
// same sequence jumps at the wrap (the test can fail).
TEST(Sequence, LoopEndsWhereItBegins) {
  const Volume stat = tiny(true);
  MotionParams m;
  m.wind_shear = 0;
  m.flow_speed = 1.0 / 30;
  const FrameRange r{3, 82};  // 80 frames at 2 fps: 40 s
  const double fps = 2, T = r.count() / fps;
  std::vector<std::string> notes;
  const MotionParams lm = loop_motion(m, T, motion_box(stat), &notes);
  EXPECT_FALSE(notes.empty());
  EXPECT_DOUBLE_EQ(lm.flow_speed * T, std::round(lm.flow_speed * T));
  for (int looped : {1, 0}) {
    const MotionParams& mm = looped ? lm : m;
    std::vector<Volume> frames;
    for (int64_t fr = r.first; fr <= r.last + 1; ++fr) frames.push_back(bake_frame(stat, mm, fr, fps).volume);
    double most = 0;
    for (size_t i = 0; i + 2 < frames.size(); ++i) most = std::max(most, rms_change(frames[i], frames[i + 1]));
    const double wrap = rms_change(frames[frames.size() - 2], frames[0]);
    double after = 0;  // frame B + 1 against frame A
    for (size_t i = 0; i < frames[0].density.size(); ++i)
      after = std::max(after, std::abs(double(frames.back().density[i]) - frames[0].density[i]));
    if (looped) {
      EXPECT_LT(after, 1e-4);
      EXPECT_LE(wrap, 1.05 * most) << "wrap " << wrap << " vs consecutive " << most;
      EXPECT_GT(wrap, 0.0);
    } else {
      EXPECT_GT(after, 0.05);
      EXPECT_GT(wrap, 2 * most);
    }
  }
  // Shear cannot loop; a box cannot loop with wind; both errors name the key.
  MotionParams sheared;
  try {
    loop_motion(sheared, T, motion_box(stat));
    ADD_FAILURE() << "shear looped";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("motion.wind_shear"), std::string::npos) << e.what();
  }
  try {
    loop_motion(m, T, motion_box(tiny(false)));
    ADD_FAILURE() << "a box looped with wind";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("motion.wind_speed"), std::string::npos) << e.what();
  }
  MotionParams calm = m;
  calm.wind_speed = 0;
  EXPECT_NO_THROW(loop_motion(calm, T, motion_box(tiny(false))));
  // A rising curl field loops by rising whole tiles of itself.
  MotionParams churn = calm;
  churn.curl_amplitude = 100;
  churn.curl_rise = 7;
  const MotionBox box = motion_box(stat);
  const MotionParams lc = loop_motion(churn, T, box);
  const double ey = box.dims[1] * box.voxel_size;
  const double tiles = lc.curl_rise * T / (ey / curl_repeats(lc, glm::dvec3(box.dims[0], box.dims[1], box.dims[2]) * box.voxel_size).y);
  EXPECT_NEAR(tiles, std::round(tiles), 1e-9);
  EXPECT_GE(std::round(tiles), 1.0);
  const Volume first = bake_frame(stat, lc, r.first, fps).volume, again = bake_frame(stat, lc, r.last + 1, fps).volume;
  double after = 0;
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < first.detail[c].size(); ++i) after = std::max(after, std::abs(double(again.detail[c][i]) - first.detail[c][i]));
  EXPECT_LT(after, 1e-4) << "the detail of frame B + 1 must be frame A's";
  ASSERT_FALSE(first.detail[0].empty());
  const Volume mid = bake_frame(stat, lc, r.first + int64_t(r.count() / 3), fps).volume;
  double churned = 0;
  for (size_t i = 0; i < first.detail[0].size(); ++i) churned = std::max(churned, std::abs(double(mid.detail[0][i]) - first.detail[0][i]));
  EXPECT_GT(churned, 0.01) << "the rising curl field must move the detail in between";
}

TEST(Sequence, FramePathsFollowBlendersNaming) {
  EXPECT_EQ(frame_path("out/cloud_####.vdb", 7), "out/cloud_0007.vdb");
  EXPECT_EQ(frame_path("out/cloud_##.vdb", 12345), "out/cloud_12345.vdb");
  EXPECT_EQ(frame_path("a#b/c_#.vdb", 3), "a#b/c_3.vdb");  // only the file name's last run
  EXPECT_EQ(frame_path("a#b/c.vdb", 3), "a#b/c.vdb");
  EXPECT_FALSE(has_frame_pattern("a#b/c.vdb"));
  EXPECT_EQ(parse_frames("4:9").count(), 6);
  EXPECT_EQ(parse_frames("5").first, 5);
  EXPECT_THROW(parse_frames("9:4"), InputError);
  EXPECT_THROW(parse_fps("0"), InputError);
}

// Bad --frames / --fps / outputs: exit 1 with a message naming the flag and what is allowed.
TEST(Sequence, BadArgumentsExitOneWithAClearMessage) {
  TempDir dir;
  const std::string o = " -o " + dir / "c_####.vdb";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--frames 9:4" + o, "--frames 9:4: the last frame is before the first"},
      {"--frames -1:4" + o, "--frames -1:4: expected A:B"},
      {"--frames 1:x" + o, "--frames 1:x: expected A:B"},
      {"--frames 0:200000" + o, "200001 frames"},
      {"--frames 0:3 --fps 0" + o, "--fps 0: expected frames per second, a number in (0, 1000]"},
      {"--frames 0:3 --fps -24" + o, "--fps -24: expected"},
      {"--frames 0:3 --fps nan" + o, "--fps nan: expected"},
      {"--frames 0:3 --fps 24x" + o, "--fps 24x: expected"},
      {"--frames 0:3 -o " + dir / "c.vdb", "no run of # for the frame number"},
      {"--frames 0:3 -o " + dir / "c_#.raw", "must be a .vdb"},
      {"--fps 24" + o, "--fps: only for sequences; add --frames"},
      {"--frames 0:3 --loop" + o, "motion.wind_shear = 0.5"},
      {"--frames 0:3 --loop --set tiling=false --set motion.wind_shear=0" + o, "motion.wind_speed = 10"},
      {"--frames 0:3 --set motion.flow_speed=11" + o, "/motion/flow_speed: 11 is out of range"},
      {"--frames 0:3 --region 0,0,0:4,4,4" + o, "--region: not available with --frames"},
      {"--frames 0:3 --max-memory 100K" + o, "more than --max-memory 100K"},
  };
  for (const auto& [args, want] : cases) {
    std::string out;
    EXPECT_EQ(run_cli("generate tiny -q " + args, &out), 1) << args << "\n" << out;
    EXPECT_NE(out.find(want), std::string::npos) << args << "\n" << out;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path)) << "a refused run wrote something";
}

// Same bytes at --threads 1 and 2 (file_checksum skips only OpenVDB's random file UUID), for a
// box volume whose frame boxes move; a one-frame run without # writes exactly the named file, and
// the metadata records the frame, its time and the motion.
TEST(Sequence, CliFramesAreDeterministicAcrossThreads) {
  TempDir dir;
  const std::string common = "generate tiny -q --set tiling=false --set motion.flow_speed=0.1 --frames 0:3 --fps 2 ";
  ASSERT_EQ(run_cli(common + "--threads 1 -o " + dir / "one/c_####.vdb"), 0);
  ASSERT_EQ(run_cli(common + "--threads 2 -o " + dir / "two/c_####.vdb"), 0);
  for (int fr = 0; fr <= 3; ++fr) {
    const std::string name = "c_000" + std::to_string(fr) + ".vdb";
    EXPECT_EQ(file_checksum(dir / ("one/" + name)), file_checksum(dir / ("two/" + name))) << name;
  }
  EXPECT_NE(file_checksum(dir / "one/c_0001.vdb"), file_checksum(dir / "one/c_0002.vdb"));
  ASSERT_EQ(run_cli("generate tiny -q --frames 5 --fps 10 -o " + dir / "single.vdb"), 0);
  const Volume v = read_vdb(dir / "single.vdb");
  auto meta = [&](const std::string& k) {
    for (const auto& [key, val] : v.metadata)
      if (key == k) return val;
    return std::string("(missing)");
  };
  EXPECT_EQ(meta("frame"), "5");
  EXPECT_EQ(meta("time_seconds"), "0.5");
  EXPECT_EQ(meta("fps"), "10");
  EXPECT_EQ(std::stod(meta("motion.flow_speed")), MotionParams{}.flow_speed);  // every digit
  EXPECT_EQ(meta("motion.wind_speed"), "10");
  EXPECT_EQ(meta("motion.box_height"), "800");
}

// All frames or none: a frame that cannot be written (its name is a link to /dev/full, which
// fails at the commit) leaves no other frame, and a folder in the frame range is refused before
// any work, keeping an older frame file as it was.
TEST(Sequence, AFailedFrameLeavesNoFrame) {
  TempDir dir;
  namespace fs = std::filesystem;
  fs::create_symlink("/dev/full", dir / "c_0002.vdb");
  std::string out;
  EXPECT_EQ(run_cli("generate tiny -q --frames 0:3 -o " + dir / "c_####.vdb", &out), 2) << out;
  EXPECT_NE(out.find("c_0002.vdb"), std::string::npos) << out;
  for (const char* f : {"c_0000.vdb", "c_0001.vdb", "c_0003.vdb"}) EXPECT_FALSE(fs::exists(dir / f)) << f << "\n" << out;
  fs::remove(dir / "c_0002.vdb");
  {
    std::ofstream(dir / "c_0001.vdb") << "old";
  }
  std::filesystem::create_directory(dir / "c_0003.vdb");
  EXPECT_EQ(run_cli("generate tiny -q --frames 0:3 -o " + dir / "c_####.vdb", &out), 1) << out;
  EXPECT_NE(out.find("c_0003.vdb: is a folder"), std::string::npos) << out;
  std::ifstream in(dir / "c_0001.vdb");
  std::string old((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(old, "old");
  EXPECT_FALSE(fs::exists(dir / "c_0000.vdb"));
}

// Interrupted sequences: Interrupted.RunLeavesNoPartialOutput (test_cloudgen.cpp).

// The preset's `motion` section is read through the parameter table: defaults = MotionParams'
// initialisers, values range-checked with the file, field, value and range, unknown keys named.
TEST(Sequence, PresetMotionSectionGoesThroughTheTable) {
  const Preset d = parse_preset("{}", "d.json");
  const MotionParams want;
  for (const MotionKey& k : motion_keys()) EXPECT_EQ(d.motion.*k.member, want.*k.member) << k.key;
  const Preset p = parse_preset(R"({"motion": {"wind_speed": 3, "flow_up": 40}})", "m.json", {"motion.wind_shear=0"});
  EXPECT_EQ(p.motion.wind_speed, 3);
  EXPECT_EQ(p.motion.flow_up, 40);
  EXPECT_EQ(p.motion.wind_shear, 0);
  auto error = [](const std::string& json) {
    try {
      parse_preset(json, "bad.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(R"({"motion": {"wind_speed": 300}})").find("bad.json: /motion/wind_speed: 300 is out of range; allowed: number in [0, 200]"),
            std::string::npos);
  EXPECT_NE(error(R"({"motion": {"wind_sped": 3}})").find("did you mean \"wind_speed\""), std::string::npos);
  EXPECT_NE(error(R"({"motion": {"flow_speed": "fast"}})").find("/motion/flow_speed: \"fast\" has the wrong type"), std::string::npos);
}

// `cloudgen blender` with a sequence: the pattern needs --frames, every frame must exist, and
// --render-frame must lie in the range (exit 1 before Blender runs).
TEST(Sequence, BlenderSequenceArgumentsAreChecked) {
  TempDir dir;
  ASSERT_EQ(run_cli("generate tiny -q --frames 0:1 -o " + dir / "c_####.vdb"), 0);
  const std::string in = dir / "c_####.vdb", o = " -o " + dir / "s.blend";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {in + o, "needs --frames A:B"},
      {in + " --frames 0:2" + o, "c_0002.vdb: no such file (frame 2 of --frames 0:2)"},
      {in + " --frames 0:1 --render-frame 5" + o, "--render-frame 5: outside --frames 0:1"},
      {dir / "c_0000.vdb --frames 0:1" + o, "--frames: only for a VDB sequence input"},
  };
  for (const auto& [args, want] : cases) {
    std::string out;
    EXPECT_EQ(run_cli("blender -q " + args, &out), 1) << args << "\n" << out;
    EXPECT_NE(out.find(want), std::string::npos) << args << "\n" << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "s.blend"));
}

// Every staged frame holds a descriptor until the commit: below the hard limit the soft one is
// raised (100 frames under a soft limit of 64), at the hard limit the run is refused up front,
// naming it, with nothing written.
TEST(Sequence, DescriptorLimitIsRaisedOrNamed) {
  TempDir dir;
  std::string out;
  EXPECT_EQ(testutil::run_shell("ulimit -Sn 64 && " + testutil::kCli + " generate tiny -q --frames 0:99 --fps 100 -o " +
                                    dir / "a/c_####.vdb", &out),
            0)
      << out;
  EXPECT_TRUE(std::filesystem::exists(dir / "a/c_0099.vdb"));
  EXPECT_EQ(testutil::run_shell("ulimit -n 64 && " + testutil::kCli + " generate tiny -q --frames 0:99 --fps 100 -o " +
                                    dir / "b/c_####.vdb", &out),
            1)
      << out;
  EXPECT_NE(out.find("100 frames are staged as open files until all are complete, but this process may open only 64 files"),
            std::string::npos)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "b"));
}

// ------------------------------------------------------------------------------ flow-map images
namespace {
/// An 8-bit PNG of `channels` (1 = grey, 3 = RGB) filled by fill(x, y, c).
template <class F>
void write_png8(const std::string& path, int w, int h, int channels, F fill) {
  std::vector<uint8_t> px(size_t(w) * h * channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) px[(size_t(y) * w + x) * channels + c] = uint8_t(fill(x, y, c));
  png_image im;
  std::memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  im.width = unsigned(w), im.height = unsigned(h), im.format = channels == 1 ? PNG_FORMAT_GRAY : PNG_FORMAT_RGB;
  ASSERT_TRUE(png_image_write_to_file(&im, path.c_str(), 0, px.data(), 0, nullptr)) << im.message;
}
}  // namespace

// `cloudgen flowmap`'s image of the procedural flow reads back as that flow: at texel centres
// within the 16-bit step, and the displacement D(h, t) from the image within the bilinear filter's
// error of the formula's (under 1% of the flow amplitudes at 256 x 64 texels).
TEST(FlowMap, ProceduralImageReadsBackAsTheProceduralFlow) {
  TempDir dir;
  write_flow_map_png(dir / "flow.png", 256, 64);
  const auto map = load_flow_map(dir / "flow.png");
  ASSERT_EQ(map->width, 256);
  ASSERT_EQ(map->height, 64);
  double texel_err = 0;
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 256; ++i) {
      const double u = (i + 0.5) / 256, h = 1.0 - j / 63.0;
      const glm::dvec2 d = map->sample(u, h) - motion_glsl::procedural_flow(glm::dvec2(u, h));
      texel_err = std::max({texel_err, std::abs(d.x), std::abs(d.y)});
    }
  EXPECT_LE(texel_err, 1.0 / 65535 + 1e-12);
  MotionParams proc, img;
  proc.flow_speed = img.flow_speed = 0.05;
  img.flow_map = map;
  MotionParams wind_only = proc;
  wind_only.flow_up = wind_only.flow_forward = 0;
  double worst = 0, biggest = 0;
  for (double t = 0; t < 40; t += 0.37)
    for (double h = 0; h <= 1.0; h += 1.0 / 37) {
      const glm::dvec3 a = motion_displacement(proc, t, h), b = motion_displacement(img, t, h);
      worst = std::max(worst, glm::length(a - b));
      biggest = std::max(biggest, glm::length(a - motion_displacement(wind_only, t, h)));
    }
  std::printf("  image flow vs procedural: max |D| difference %.3f m (flow amplitude %.0f / %.0f m, largest flow %.1f m)\n",
              worst, proc.flow_up, proc.flow_forward, biggest);
  EXPECT_GT(biggest, 100.0);  // the flow does move the cloud
  EXPECT_LT(worst, 0.01 * proc.flow_forward);
}

// A baked frame with an image flow map is the static volume at p - D(h, t) of that map; a coarse
// map (8 x 4 texels) moves the cloud differently from the procedural flow.
TEST(FlowMap, BakedFrameFollowsTheImage) {
  TempDir dir;
  write_flow_map_png(dir / "coarse.png", 8, 4);
  const Volume stat = tiny(false);
  MotionParams m;
  m.wind_speed = 2;
  m.flow_speed = 0.05;
  MotionParams mi = m;
  mi.flow_map = load_flow_map(dir / "coarse.png");
  const MotionFrame f = bake_frame(stat, mi, 70, 10.0, 2);
  const Compare c = compare_frame(stat, mi, f);
  EXPECT_LT(c.max_err, 1e-5);
  EXPECT_EQ(c.outside, 0.0);
  const Compare other = compare_frame(stat, m, f);  // against the procedural flow's positions
  EXPECT_GT(other.max_err, 0.05);
}

// Bad flow maps: the message names the key, the file and what is wrong; nothing is half-set.
TEST(FlowMap, BadFilesAreRefusedWithTheReason) {
  TempDir dir;
  std::ofstream(dir / "text.png") << "not an image";
  write_png8(dir / "grey.png", 4, 4, 1, [](int x, int, int) { return x * 60; });
  std::filesystem::create_directory(dir / "folder.png");
  auto error = [](const std::string& path) {
    MotionParams m;
    try {
      set_motion_key(m, "flow_map", path, "--set");
    } catch (const InputError& e) {
      EXPECT_FALSE(m.flow_map) << path;
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(dir / "missing.png").find("--set motion.flow_map " + (dir / "missing.png") + ": no such file"), std::string::npos);
  EXPECT_NE(error(dir / "text.png").find("not a PNG file"), std::string::npos);
  EXPECT_NE(error(dir / "grey.png").find("a grey image"), std::string::npos);
  EXPECT_NE(error(dir / "folder.png").find("--set motion.flow_map " + (dir / "folder.png") + ": is a folder, not a file"),
            std::string::npos)
      << error(dir / "folder.png");
  EXPECT_NE(error("").find("give a PNG file or \"procedural\""), std::string::npos);
  // Wider than the limit: refused from the header, before any texel is stored.
  write_png8(dir / "wide.png", kFlowMapMaxSide + 1, 1, 3, [](int, int, int) { return 128; });
  EXPECT_NE(error(dir / "wide.png").find("4097 x 1 texels; a flow map may have at most 4096 a side"), std::string::npos)
      << error(dir / "wide.png");
  // An 8-bit RGB map: 0 -> -1, 255 -> +1 per channel, R = up, G = forward.
  write_png8(dir / "rgb.png", 2, 1, 3, [](int x, int, int c) { return c == 0 ? x * 255 : 255 - x * 255; });
  MotionParams m;
  set_motion_key(m, "flow_map", dir / "rgb.png", "--set");
  ASSERT_TRUE(m.flow_map);
  EXPECT_EQ(m.flow_map->texels[0], glm::dvec2(-1, 1));
  EXPECT_EQ(m.flow_map->texels[1], glm::dvec2(1, -1));
  EXPECT_EQ(flow_map_name(m), dir / "rgb.png");
  set_motion_key(m, "flow_map", "procedural", "--set");
  EXPECT_FALSE(m.flow_map);
}

// In a preset, a relative flow_map is found next to the preset; with --set, from the current
// folder; a bad one is a preset problem naming /motion/flow_map.
TEST(FlowMap, PresetPathsResolveFromThePresetsFolder) {
  TempDir dir;
  std::filesystem::create_directory(dir / "p");
  write_flow_map_png(dir / "p/flow.png", 16, 8);
  std::ofstream(dir / "p/moving.json") << R"({"resolution": [16, 8, 16], "motion": {"flow_map": "flow.png"}})";
  const Preset p = load_preset(dir / "p/moving.json");
  ASSERT_TRUE(p.motion.flow_map);
  EXPECT_EQ(p.motion.flow_map->width, 16);
  try {
    load_preset(dir / "p/moving.json", {"motion.flow_map=flow.png"});  // from the current folder: not there
    ADD_FAILURE() << "a --set flow map was looked up next to the preset";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/motion/flow_map: motion.flow_map flow.png: no such file"), std::string::npos) << e.what();
  }
  const Preset q = load_preset(dir / "p/moving.json", {"motion.flow_map=" + (dir / "p/flow.png")});
  EXPECT_TRUE(q.motion.flow_map);
  const Preset r = load_preset(dir / "p/moving.json", {"motion.flow_map=procedural"});
  EXPECT_FALSE(r.motion.flow_map);
  // The CLI: flowmap writes one, a sequence bakes with it and records it in the frame's metadata.
  std::string out;
  ASSERT_EQ(run_cli("flowmap -q --size 32x8 -o " + (dir / "f.png"), &out), 0) << out;
  ASSERT_EQ(run_cli("generate " + kPresets + "tiny.json -q --set motion.flow_map=" + (dir / "f.png") +
                        " --frames 1:2 --fps 4 -o " + (dir / "c_##.vdb"),
                    &out),
            0)
      << out;
  ASSERT_EQ(run_cli("info " + (dir / "c_02.vdb"), &out), 0) << out;
  EXPECT_NE(out.find(dir / "f.png"), std::string::npos) << out;
}
