// Game-engine texture pack (issue 44 item 4; cloudgen/texture_pack.h, docs/textures.md): the files
// and their declared sizes, every KTX2 with its mips through the project's own reader, each mip the
// box filter of the one above, tileable textures wrapping, the KTX2 reader refusing damaged level
// indexes, pack.json errors naming the field, and the pack written all or nothing.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cloudgen/errors.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudgen/texture_pack.h"
#include "test_util.h"

using namespace cloudgen;
using namespace testutil;
using nlohmann::json;

namespace {

// One pack of tiny (32^3, rescaled to 128 on its longest axis by the pack) made by the CLI, shared.
const std::string& cli_pack() {
  static TempDir dir;
  static std::string pack;
  if (pack.empty()) {
    std::string out;
    const int code = run_cli("generate " + kPresets + "tiny.json -q --threads 2 --texture-pack " + dir / "pack", &out);
    EXPECT_EQ(code, 0) << out;
    pack = dir / "pack";
  }
  return pack;
}

std::vector<uint8_t> bytes_of(const std::string& path) { return read_file_bytes(path); }

// Mean absolute byte difference between the texels of two faces of a 3D/2D level, along `axis`:
// the last slice against the first (what a wrap puts side by side), and neighbouring inner slices.
void face_gaps(const MipTexture& t, int axis, double* across, double* inside) {
  const auto& d = t.dims;
  const std::vector<uint8_t>& l = t.levels[0];
  auto at = [&](uint32_t x, uint32_t y, uint32_t z, int c) {
    return double(l[((size_t(z) * d[1] + y) * d[0] + x) * size_t(t.channels) + size_t(c)]);
  };
  double a = 0, b = 0;
  size_t n = 0;
  const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : (axis == 1 ? 2 : 2);
  for (uint32_t i = 0; i < d[u]; ++i)
    for (uint32_t j = 0; j < d[v]; ++j)
      for (int c = 0; c < t.channels; ++c) {
        std::array<uint32_t, 3> p{{0, 0, 0}}, q{{0, 0, 0}};
        p[u] = q[u] = i;
        p[v] = q[v] = j;
        p[axis] = d[axis] - 1;
        q[axis] = 0;
        a += std::abs(at(p[0], p[1], p[2], c) - at(q[0], q[1], q[2], c));
        p[axis] = d[axis] / 2;
        q[axis] = d[axis] / 2 + 1;
        b += std::abs(at(p[0], p[1], p[2], c) - at(q[0], q[1], q[2], c));
        ++n;
      }
  *across = a / n;
  *inside = b / n;
}

}  // namespace

TEST(TexturePack, KtxMipChainRoundTripsAndEachMipIsTheBoxFilter) {
  MipTexture t;
  t.dims = {6, 5, 3};  // odd edges: 6x5x3 -> 3x2x1 -> 1x1x1
  t.channels = 3;
  t.levels = {std::vector<uint8_t>(6 * 5 * 3 * 3)};
  uint32_t h = 7;
  for (uint8_t& b : t.levels[0]) b = uint8_t((h = h * 1664525u + 1013904223u) >> 24);
  build_mips(t);
  ASSERT_EQ(t.levels.size(), 3u);
  EXPECT_EQ(mip_dims(t.dims, 1), (std::array<uint32_t, 3>{{3, 2, 1}}));
  EXPECT_EQ(t.levels[2].size(), 3u);
  // Level 1 texel (0,0,0) channel 0 by hand: the mean of the 8 texels x 0-1, y 0-1, z 0-1, rounded.
  uint32_t sum = 0;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) sum += t.levels[0][size_t((z * 5 + y) * 6 + x) * 3];
  EXPECT_EQ(t.levels[1][0], uint8_t((sum + 4) / 8));
  const std::vector<uint8_t> file = ktx2_bytes(t);
  const MipTexture r = parse_ktx2_mips(file, "t.ktx2");
  EXPECT_EQ(r.dims, t.dims);
  EXPECT_EQ(r.channels, 3);
  EXPECT_TRUE(r.is_3d);
  EXPECT_EQ(r.levels, t.levels);
  // Level data smallest first, as the specification orders it; each offset aligned to lcm(3, 4).
  uint64_t off[3];
  for (int l = 0; l < 3; ++l) {
    std::memcpy(&off[l], file.data() + 80 + 24 * l, 8);
    EXPECT_EQ(off[l] % 12, 0u) << l;
  }
  EXPECT_LT(off[2], off[1]);
  EXPECT_LT(off[1], off[0]);
}

TEST(TexturePack, KtxReaderRefusesDamagedLevelIndexes) {
  MipTexture t;
  t.dims = {8, 8, 1};
  t.is_3d = false;
  t.channels = 4;
  t.levels = {std::vector<uint8_t>(8 * 8 * 4, 100)};
  build_mips(t);
  const std::vector<uint8_t> good = ktx2_bytes(t);
  ASSERT_EQ(parse_ktx2_mips(good, "g.ktx2").levels.size(), 4u);
  auto damaged = [&](size_t at, uint64_t value, int width) {
    std::vector<uint8_t> b = good;
    std::memcpy(b.data() + at, &value, size_t(width));
    return b;
  };
  struct Case {
    size_t at;
    uint64_t value;
    int width;
    const char* says;
  } cases[] = {
      {40, 5, 4, "levelCount 5 is outside [1, 4]"},
      {40, 0, 4, "levelCount 0"},
      {80 + 24 * 2, good.size(), 8, "level 2"},                 // offset past the end
      {80 + 24 * 3 + 8, 5, 8, "level 3 (byteLength 5"},         // wrong length
      {80 + 24 * 1 + 16, 3, 8, "uncompressedByteLength 3"},     // wrong uncompressed length
      {80 + 24 * 0, uint64_t(-8), 8, "level 0"},                // offset + length overflows
      {80 + 24 * 1, 1, 8, "aligned to 4"},                      // misaligned
      {12, 97, 4, "vkFormat 97"},
      {24, 0, 4, "pixelHeight 0"},
  };
  for (const Case& c : cases) {
    try {
      parse_ktx2_mips(damaged(c.at, c.value, c.width), "d.ktx2");
      ADD_FAILURE() << "accepted: " << c.says;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    }
  }
  // Truncated anywhere: refused, never read past the end.
  for (size_t n : {size_t(0), size_t(79), size_t(100), good.size() - 1}) {
    const std::vector<uint8_t> b(good.begin(), good.begin() + long(n));
    EXPECT_THROW(parse_ktx2_mips(b, "t.ktx2"), InputError) << n;
  }
}

TEST(TexturePack, FilesHaveTheDeclaredSizesAndMipsAndPassTheKtxReaders) {
  const std::string dir = cli_pack();
  const json pj = json::parse(read_text(dir + "/pack.json"));
  EXPECT_EQ(pj["format"], "cloudgen-texture-pack");
  const std::array<uint32_t, 3> want[4] = {{{128, 128, 128}}, {{32, 32, 32}}, {{128, 128, 1}}, {{128, 128, 1}}};
  const int channels[4] = {4, 3, 3, 3};
  const char* roles[4] = {"base", "detail", "curl", "weather"};
  ASSERT_EQ(pj["textures"].size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const json& tj = pj["textures"][size_t(i)];
    EXPECT_EQ(tj["role"], roles[i]);
    const MipTexture t = parse_ktx2_mips(bytes_of(dir + "/" + tj["ktx2"].get<std::string>()), roles[i]);
    EXPECT_EQ(t.dims, want[i]) << roles[i];
    EXPECT_EQ(t.channels, channels[i]) << roles[i];
    EXPECT_EQ(t.is_3d, i < 2) << roles[i];
    EXPECT_EQ(t.levels.size(), full_mip_count(want[i])) << roles[i];
    EXPECT_EQ(tj["mips"], t.levels.size()) << roles[i];
    EXPECT_EQ(t.levels.back().size(), size_t(channels[i])) << roles[i] << ": down to one texel";
    for (size_t l = 1; l < t.levels.size(); ++l)
      EXPECT_EQ(t.levels[l], box_downsample(t.levels[l - 1], mip_dims(t.dims, uint32_t(l - 1)), t.channels))
          << roles[i] << " mip " << l;
    // The raw file: the same levels, largest first, at the offsets pack.json gives.
    const std::vector<uint8_t> raw = bytes_of(dir + "/" + tj["raw"].get<std::string>());
    for (size_t l = 0; l < t.levels.size(); ++l) {
      const size_t off = tj["raw_levels"][l]["offset"], n = tj["raw_levels"][l]["bytes"];
      ASSERT_LE(off + n, raw.size());
      EXPECT_TRUE(std::equal(t.levels[l].begin(), t.levels[l].end(), raw.begin() + long(off))) << roles[i] << " " << l;
    }
    for (const json& p : tj["period_m"]) EXPECT_GT(p.get<double>(), 0.0);
  }
  // The base KTX2 also passes the volume reader (level 0) as the preset's volume at 128 voxels.
  const Volume v = read_ktx2(dir + "/base.ktx2");
  EXPECT_EQ(v.dims, (std::array<uint32_t, 3>{{128, 128, 128}}));
  EXPECT_EQ(v.detail[0].size(), v.voxel_count()) << "tiny's channel g";
  EXPECT_TRUE(v.detail[2].empty()) << "tiny has no channel a";
  EXPECT_EQ(pj["textures"][0]["channels"]["a"], "0 (the preset has no channel a)");
  EXPECT_DOUBLE_EQ(v.voxel_size * 128, pj["extent_m"][0].get<double>());
  // And the whole pack through its reader.
  const Volume w = read_texture_pack(dir + "/pack.json");
  EXPECT_EQ(w.density, v.density);
}

TEST(TexturePack, TileableTexturesWrap) {
  const std::string dir = cli_pack();
  // tiny tiles in x and z, so the base does too; detail and curl tile on every axis.
  for (const char* role : {"detail", "curl", "base"}) {
    const MipTexture t = parse_ktx2_mips(bytes_of(dir + "/" + role + ".ktx2"), role);
    for (int axis : {0, 1, 2}) {
      if (t.dims[axis] < 4 || (std::string(role) == "base" && axis == 1)) continue;
      double across = 0, inside = 0;
      face_gaps(t, axis, &across, &inside);
      // Across the wrap the texture continues: no larger a step than between inner neighbours.
      EXPECT_LT(across, 1.5 * inside + 1.0) << role << " axis " << axis << ": " << across << " vs " << inside;
    }
  }
}

TEST(TexturePack, PackJsonErrorsNameTheField) {
  const std::string dir = cli_pack();
  const json good = json::parse(read_text(dir + "/pack.json"));
  EXPECT_NO_THROW(parse_pack_json(good.dump(), "pack.json"));
  struct Case {
    std::function<void(json&)> edit;
    const char* says;
  } cases[] = {
      {[](json& j) { j["format"] = "zip"; }, "\"format\" is \"zip\""},
      {[](json& j) { j["version"] = 9; }, "version"},
      {[](json& j) { j["textures"].erase(3); }, "the 4 textures"},
      {[](json& j) { j["textures"][1]["role"] = "base"; }, "textures[1]: \"role\" is \"base\""},
      {[](json& j) { j["textures"][0]["ktx2"] = "../../etc/passwd"; }, "a file name inside the pack's folder"},
      {[](json& j) { j["textures"][0]["size"] = {128, 0, 128}; }, "\"size\"[1] is 0"},
      {[](json& j) { j["textures"][2]["dimension"] = 3; }, "the curl texture is 2D"},
      {[](json& j) { j["textures"][0]["format"] = "rgb8_unorm"; }, "the base texture is rgba8_unorm"},
      {[](json& j) { j["textures"][1]["mips"] = 9; }, "mips"},
      {[](json& j) { j["textures"][3]["period_m"] = {-1, 2}; }, "\"period_m\"[0] is -1"},
      {[](json& j) { j["extent_m"] = {0, 1, 1}; }, "extent_m"},
  };
  for (const Case& c : cases) {
    json j = good;
    c.edit(j);
    try {
      parse_pack_json(j.dump(), "pack.json");
      ADD_FAILURE() << "accepted: " << c.says;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("pack.json"), std::string::npos) << e.what();
    }
  }
  // A pack whose KTX2 disagrees with pack.json, or whose mip was tampered with, is refused on reading.
  TempDir t;
  std::filesystem::copy(dir, t / "p");
  std::vector<uint8_t> k = bytes_of(t / "p/detail.ktx2");
  k[k.size() - 1] ^= 0x40;  // the largest level is stored last: a texel of level 0
  write_text(t / "p/detail.ktx2", std::string(k.begin(), k.end()));
  try {
    read_texture_pack(t / "p/pack.json");
    ADD_FAILURE() << "a damaged level 0 passed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is not the 2x box filter"), std::string::npos) << e.what();
  }
}

TEST(TexturePack, AllOrNothing) {
  TempDir t;
  std::string out;
  // The folder name is taken by a file: refused before any work, exit 1, nothing written.
  write_text(t / "taken", "x");
  EXPECT_EQ(run_cli("generate " + kPresets + "tiny.json -q -o " + t / "a.vdb" + " --texture-pack " + t / "taken", &out), 1) << out;
  EXPECT_NE(out.find("exists and is not a folder"), std::string::npos) << out;
  EXPECT_EQ(list_dir(t.path), (std::vector<std::string>{"taken"}));
  // An -o output that is one of the pack's files: refused up front, no folder made.
  EXPECT_EQ(run_cli("generate " + kPresets + "tiny.json -q -o " + t / "p/base.raw" + " --texture-pack " + t / "p", &out), 1) << out;
  EXPECT_EQ(list_dir(t.path), (std::vector<std::string>{"taken"})) << out;
  // An unwritable folder: exit 2 (I/O), the other output not written either, no debris.
  if (::geteuid() != 0) {
    std::filesystem::create_directory(t / "ro");
    ::chmod((t / "ro").c_str(), 0555);
    EXPECT_EQ(run_cli("generate " + kPresets + "tiny.json -q -o " + t / "a.vdb" + " --texture-pack " + t / "ro", &out), 2) << out;
    EXPECT_TRUE(list_dir(t.path / "ro").empty());
    EXPECT_FALSE(std::filesystem::exists(t / "a.vdb"));
  }
  // A small "disk" that fills while the pack is written: exit 2, no pack, no VDB, no folder.
  Process p;
  p.args = {"generate", kPresets + "tiny.json", "-q", "-o", t / "b.vdb", "--texture-pack", t / "q"};
  p.fsize_limit = 1 << 20;  // the base KTX2 alone is 9.6 MB
  const Process::Result r = p.run();
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(list_dir(t.path), (std::vector<std::string>{"taken"})) << r.out;
}

// kill -9 used to leave an empty DIR behind (the folder was made when the batch claimed its
// files). A new pack folder is staged beside DIR and appears whole at the commit, or not at all:
// killed while generating or just before the commit, nothing is left; a temporary folder that a
// run killed inside its commit left is removed by the next run, which writes the pack whole; an
// existing folder keeps the current rule (its pack files replaced, the user's other files kept).
TEST(TexturePack, AKilledRunLeavesNoFolderAndTheNextRunWritesItWhole) {
  TempDir t;
  for (const char* hold : {"generate", "commit"}) {
    Process p;
    p.args = {"generate", kPresets + "tiny.json", "-q", "-o", t / "a.vdb", "--texture-pack", t / "pack"};
    p.env = {std::string("CLOUDGEN_TEST_HOLD=") + hold};
    p.signal_on = std::string("test hold at ") + hold;
    p.sig = SIGKILL;
    const Process::Result r = p.run();
    EXPECT_EQ(r.term_signal, SIGKILL) << hold << ": " << r.out;
    EXPECT_TRUE(list_dir(t.path).empty()) << hold << ": nothing may survive kill -9: " << r.out;
  }
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  const std::string stale = ".pack.tmp-" + std::to_string(child) + "-0";
  std::filesystem::create_directory(t / stale);
  write_text(t / stale + "/base.ktx2", "a half-published pack");
  std::filesystem::create_directory(t / ".pack.tmp-notapid-0");  // not a temporary of ours: kept
  std::string out;
  ASSERT_EQ(run_cli("generate " + kPresets + "tiny.json -q --threads 2 --texture-pack " + t / "pack", &out), 0) << out;
  EXPECT_EQ(list_dir(t.path), (std::vector<std::string>{".pack.tmp-notapid-0", "pack"}));
  const std::vector<std::string> files = {"base.ktx2",   "base.raw",   "curl.ktx2",    "curl.raw",   "detail.ktx2",
                                          "detail.raw",  "pack.json",  "weather.ktx2", "weather.raw"};
  EXPECT_EQ(list_dir(t / "pack"), files);
  for (const std::string& f : files) EXPECT_EQ(bytes_of(t / "pack/" + f), bytes_of(cli_pack() + "/" + f)) << f;
  write_text(t / "pack/notes.txt", "mine");
  write_text(t / "pack/base.raw", "old");
  ASSERT_EQ(run_cli("generate " + kPresets + "tiny.json -q --threads 2 --texture-pack " + t / "pack", &out), 0) << out;
  EXPECT_EQ(read_text(t / "pack/notes.txt"), "mine");
  EXPECT_EQ(bytes_of(t / "pack/base.raw"), bytes_of(cli_pack() + "/base.raw"));
}

TEST(TexturePack, SameBytesForAnyThreadCount) {
  TempDir t;
  std::string out;
  ASSERT_EQ(run_cli("generate " + kPresets + "tiny.json -q --threads 1 --texture-pack " + t / "one", &out), 0) << out;
  for (const char* f : {"base.ktx2", "detail.ktx2", "curl.ktx2", "weather.ktx2", "base.raw", "pack.json"})
    EXPECT_EQ(bytes_of(t / "one/" + f), bytes_of(cli_pack() + "/" + f)) << f;
}
