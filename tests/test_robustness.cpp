// Nothing lost, nothing crashes: output safety (devices, links, full disks, collisions, several
// outputs all or nothing, no debris), hostile inputs (truncated and damaged files, deep or duplicate
// JSON, out-of-range flags), exit codes, and every preset key at the ends of its range.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "cloudgen/cli_parse.h"
#include "cloudgen/exit_codes.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/nvdb.h"
#include "cloudgen/preset.h"
#include "test_util.h"

using namespace cloudgen;
using namespace testutil;
namespace fs = std::filesystem;

namespace {

Process cli(std::vector<std::string> args) {
  Process p;
  p.args = std::move(args);
  return p;
}

bool is_char_device(const std::string& p) {
  struct stat st;
  return ::lstat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return std::string("input: ") + e.what();
  } catch (const IoError& e) {
    return std::string("io: ") + e.what();
  }
  return "";
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Output safety

TEST(OutputSafety, DeviceNodesAreWrittenThroughNeverReplaced) {
  auto r = cli({"generate", "tiny", "-q", "--format", "vdb", "-o", "/dev/full"}).run();
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("/dev/full"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("No space left on device"), std::string::npos) << r.out;
  EXPECT_TRUE(is_char_device("/dev/full")) << "the device node must survive";
  r = cli({"generate", "tiny", "-q", "--format", "vdb", "-o", "/dev/null"}).run();
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(is_char_device("/dev/null"));
}

TEST(OutputSafety, FifoIsWrittenThrough) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "pipe.ktx2").c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = read_text(dir / "pipe.ktx2"); });
  auto r = cli({"generate", "tiny", "-q", "-o", dir / "pipe.ktx2"}).run();
  reader.join();
  EXPECT_EQ(r.code, 0) << r.out;
  ASSERT_EQ(r.code, 0);
  auto r2 = cli({"generate", "tiny", "-q", "-o", dir / "file.ktx2"}).run();
  ASSERT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(got, read_text(dir / "file.ktx2")) << "the bytes through the FIFO equal the regular file's";
  struct stat st;
  ASSERT_EQ(::lstat((dir / "pipe.ktx2").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO must not be replaced by a file";
}

// Issue 47, D1 and item 1: a FIFO output with no reader is waited for, and a signal ends the wait
// (exit 130, the FIFO kept); a FIFO *input* is refused at once by every reader (one rule, in
// protect_input), since nothing guarantees a writer or an end.
TEST(Interrupts, AFifoOutputWithNoReaderEndsOnTheSignal) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "f.vdb").c_str(), 0600), 0);
  Process p = cli({"generate", "tiny", "-q", "-o", dir / "f.vdb"});
  p.signal_on = "waiting for a reader";
  p.sig = SIGTERM;
  const auto r = p.run();
  ASSERT_TRUE(r.signalled) << r.out;
  EXPECT_EQ(r.code, 130) << r.out;
  EXPECT_NE(r.out.find("no output was written or replaced"), std::string::npos) << r.out;
  struct stat st;
  ASSERT_EQ(::lstat((dir / "f.vdb").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST(Interrupts, PipeInputsAreRefusedByEveryReader) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "p.json").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "p.vdb").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "p.png").c_str(), 0600), 0);
  const std::string json = dir / "p.json", vdb = dir / "p.vdb", png = dir / "p.png";
  // The same words for every input, the flow map and the painted weather map included (they once
  // had checks of their own beside the input layer).
  const std::string fifo = ": is a pipe (FIFO), not a regular file; every input must be a regular file";
  const std::vector<std::vector<std::string>> runs = {
      {"validate", json}, {"generate", json, "-q", "-o", dir / "o.vdb"}, {"info", json}, {"info", vdb},
      {"plan", json, "--tiles", "2,1,1", "-o", dir / "plan.json"}, {"merge", json, "-o", dir / "m.vdb"},
      {"generate", "tiny", "-q", "--set", "motion.flow_map=" + png, "-o", dir / "o.vdb"},
      {"generate", "tiny", "-q", "--set", "coverage.enabled=true", "--set", "coverage.kind=image", "--set",
       "coverage.file=" + png, "-o", dir / "o.vdb"}};
  for (const auto& args : runs) {
    const auto r = cli(args).run();
    EXPECT_EQ(r.code, 1) << args[0] << ": " << r.out;
    const std::string& input = args[1] == "tiny" ? png : args[1];
    EXPECT_NE(r.out.find(input + fifo), std::string::npos) << args[0] << ": " << r.out;
  }
  Process v = cli({json, "--headless", "--size", "16x9", "--out", dir / "a.png"});
  v.program = std::string(CLOUD_BINARY_DIR) + "/bin/cloudviewer";
  if (fs::exists(v.program)) {
    auto r = v.run();
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(json + fifo), std::string::npos) << r.out;
    v.args = {"synthetic:sphere", "--mie-table", png, "--set", "render.phase=mie", "--headless", "--size", "16x9",
              "--out", dir / "a.png"};
    r = v.run();
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(png + fifo), std::string::npos) << r.out;
  }
  EXPECT_EQ(list_dir(dir.path), (std::vector<std::string>{"p.json", "p.png", "p.vdb"}));
}

// Work that cannot poll the cancel flag (the test hold "generate:stuck" stands for a call blocked
// inside a library) is ended by the policy's forced exit after the signal: 130, its words, no output.
TEST(Interrupts, WorkThatCannotPollIsEndedByTheForcedExit) {
  TempDir dir;
  write_text(dir / "old.vdb", "previous contents");
  for (int sig : {SIGINT, SIGTERM}) {
    Process p = cli({"generate", "cumulus-field", "--resolution", "64", "-q", "-o", dir / "old.vdb", "-o", dir / "new.ktx2"});
    p.env = {"CLOUDGEN_TEST_HOLD=generate:stuck"};
    p.signal_on = "test hold at generate";
    p.sig = sig;
    const auto r = p.run();
    ASSERT_TRUE(r.signalled) << r.out;
    EXPECT_EQ(r.code, 130) << "signal " << sig << ": " << r.out;
    EXPECT_NE(r.out.find("interrupted: no output was written or replaced"), std::string::npos) << r.out;
    EXPECT_EQ(list_dir(dir.path), std::vector<std::string>{"old.vdb"});
    EXPECT_EQ(read_text(dir / "old.vdb"), "previous contents");
  }
}

// A closed stdout pipe (`cloudgen presets --markdown | head -1` once head has quit) ends the
// program quietly with 141, as Unix tools do.
TEST(Interrupts, AClosedStdoutPipeEndsQuietlyWith141) {
  Process p = cli({"presets", "--markdown"});
  p.stdout_closed = true;
  const auto r = p.run();
  EXPECT_EQ(r.code, 141) << r.out;
  EXPECT_EQ(r.out, "") << "nothing said on stderr";
}

// Issue 47, D2 and D3: a text input has a cap checked before it is read, and --resolution has the
// preset table's range, so no memory estimate can overflow.
TEST(InputBounds, TextInputsAreCappedAndResolutionHasTheTablesRange) {
  TempDir dir;
  {
    std::ofstream f(dir / "huge.json");
  }
  fs::resize_file(dir / "huge.json", (uint64_t(64) << 20) + 1);  // sparse: costs no disk
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"validate", dir / "huge.json"}, {"merge", dir / "huge.json", "-o", dir / "m.vdb"}}) {
    const auto r = cli(args).run();
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("67108865 bytes is more than the 64 MiB this reader accepts"), std::string::npos) << r.out;
  }
  for (const char* cmd : {"generate", "plan"}) {
    const auto r = cli({cmd, "tiny", "--resolution", "2147483648", "-o", dir / "t.vdb"}).run();
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("--resolution: 2147483648 is out of range [1, 4096]"), std::string::npos) << r.out;
  }
  EXPECT_EQ(list_dir(dir.path), std::vector<std::string>{"huge.json"});
}

// Issue 47, D10 and D11, item 5: a plan is untrusted input. Each edit below is refused (exit 1)
// before any tile is read or regenerated, even with --resume, and nothing is written anywhere.
TEST(PlansAreUntrusted, EveryEditMergeCannotAccountForIsRefused) {
  TempDir dir;
  fs::create_directory(dir / "plan");
  const std::string plan = dir / "plan/plan.json";
  ASSERT_EQ(cli({"plan", "tiny", "--tiles", "2,1,1", "-o", plan}).run().code, 0);
  write_text(dir / "victim.txt", "precious");
  const nlohmann::json good = nlohmann::json::parse(read_text(plan));
  const struct {
    std::function<void(nlohmann::json&)> edit;
    const char* says;
  } cases[] = {
      {[](auto& d) { d["tiles"][1]["file"] = "../victim.txt"; }, "is not a plain file name"},
      {[&](auto& d) { d["tiles"][1]["file"] = dir / "victim.txt"; }, "is not a plain file name"},
      {[](auto& d) { d["tiles"][1]["file"] = d["tiles"][0]["file"]; }, "is already another tile's"},
      {[](auto& d) { d["tiles"] = nlohmann::json::array(); }, "0 tiles listed"},
      {[](auto& d) { d["cloudgen_plan"] = 999; }, "plan version 999"},
      {[](auto& d) { d["resolution"] = {2147483648u, 1, 1}; }, "\"resolution\" is [2147483648,1,1]; allowed"},
      {[](auto& d) { d["tiles_per_axis"] = {0, 1, 1}; }, "\"tiles_per_axis\" is [0,1,1]; allowed"},
      {[](auto& d) { d["tiles"][1]["region"] = "-1,0,0:8,8,8"; }, "is not X,Y,Z:W,H,D"},
      {[](auto& d) { d["tiles"][1]["region"] = d["tiles"][0]["region"]; }, "overlaps tile 0's"},
      {[](auto& d) { d["tiles"][1]["index"] = "x"; }, "\"index\" is \"x\", not a whole number"},
      {[](auto& d) { d["tiles"][1].erase("command"); }, "no \"command\""},
      {[](auto& d) { d["args"] = {"--resolution", "abc"}; }, "--resolution \"abc\"; allowed"},
  };
  for (const auto& c : cases) {
    nlohmann::json d = good;
    c.edit(d);
    write_text(dir / "plan/bad.json", d.dump());
    const auto r = cli({"merge", dir / "plan/bad.json", "--resume", "-q", "-o", dir / "out.vdb"}).run();
    EXPECT_EQ(r.code, 1) << c.says << ": " << r.out;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << r.out;
  }
  EXPECT_EQ(read_text(dir / "victim.txt"), "precious");
  EXPECT_EQ(list_dir(dir / "plan"), (std::vector<std::string>{"bad.json", "plan.json"}));
  EXPECT_EQ(list_dir(dir.path), (std::vector<std::string>{"plan", "victim.txt"}));
}

// Issue 47, D14 and D17 (item 7): what a program prints is checked like any file (a full disk under
// `> file` is exit 2 with the system's reason), and no option value means something it does not
// say: empty values, NaN, and integers that round into the range are refused.
TEST(Words, StdoutIsCheckedAndValuesAreRefusedAsTyped) {
  const std::string viewer = std::string(CLOUD_BINARY_DIR) + "/bin/cloudviewer";
  const bool has_viewer = fs::exists(viewer);
  std::string out;
  EXPECT_EQ(run_shell("(" + kCli + " presets --markdown > /dev/full)", &out), 2) << out;
  EXPECT_NE(out.find("writing to standard output failed: No space left on device"), std::string::npos) << out;
  if (has_viewer) {
    EXPECT_EQ(run_shell("(" + viewer + " --params-markdown > /dev/full)", &out), 2) << out;
    EXPECT_NE(out.find("No space left on device"), std::string::npos) << out;
  }
  TempDir dir;
  const struct {
    std::string cmd, says;
  } refused[] = {
      {kCli + " phase --model hg --g nan -o " + (dir / "p.csv"), "--g: \"nan\" is not a finite number"},
      {kCli + " generate tiny --resolution '' -o " + (dir / "t.vdb"), "--resolution: an empty value"},
      {kCli + " generate tiny --region '' -o " + (dir / "t.vdb"), "--region: an empty value"},
      {kCli + " generate tiny --set seed=9007199254740993 -o " + (dir / "t.vdb"),
       "/seed: 9007199254740993 is out of range; allowed: integer in [0, 9007199254740992]"},
      {has_viewer ? viewer + " synthetic:sphere --headless --size 16x9 --frames 2 --fps nan --out " + (dir / "f_%d.png") : "",
       "--fps: \"nan\" is not a finite number"},
      {has_viewer ? viewer + " synthetic:sphere --headless --size 16x9 --fov '' --out " + (dir / "f.png") : "",
       "--fov: an empty value"},
  };
  for (const auto& r : refused) {
    if (r.cmd.empty()) continue;
    EXPECT_EQ(run_shell(r.cmd, &out), 1) << r.cmd << ": " << out;
    EXPECT_NE(out.find(r.says), std::string::npos) << r.cmd << ": " << out;
  }
  EXPECT_TRUE(list_dir(dir.path).empty());
}

// Issue 47, D15: every legal output name can be written, up to 255 bytes, replacing an old file
// too (the temporary and the backup link have names of their own that must fit).
TEST(OutputSafety, TheLongestLegalNamesAreWritten) {
  TempDir dir;
  const std::string name = std::string(251, 'a') + ".vdb";  // 255 bytes
  ASSERT_EQ(cli({"generate", "tiny", "-q", "-o", dir / name}).run().code, 0);
  const auto r = cli({"generate", "tiny", "-q", "--seed", "4", "-o", dir / name}).run();
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(list_dir(dir.path), std::vector<std::string>{name});
}

TEST(OutputSafety, SymlinkTargetIsReplacedAndTheLinkStays) {
  TempDir dir;
  fs::create_directory(dir / "real");
  write_text(dir / "real/cloud.ktx2", "old");
  fs::create_symlink("real/cloud.ktx2", dir / "link.ktx2");
  fs::create_symlink("real/new.ktx2", dir / "dangling.ktx2");
  for (const char* out : {"link.ktx2", "dangling.ktx2"}) {
    auto r = cli({"generate", "tiny", "-q", "-o", dir / out}).run();
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::is_symlink(dir / out)) << out;
  }
  EXPECT_GT(fs::file_size(dir / "real/cloud.ktx2"), 1000u);
  EXPECT_GT(fs::file_size(dir / "real/new.ktx2"), 1000u);
  EXPECT_EQ(list_dir(dir.path), (std::vector<std::string>{"dangling.ktx2", "link.ktx2", "real"}));
  EXPECT_EQ(list_dir(dir.path / "real"), (std::vector<std::string>{"cloud.ktx2", "new.ktx2"}));
}

TEST(OutputSafety, FoldersAndBlockDevicesAreRefused) {
  TempDir dir;
  fs::create_directory(dir / "x.vdb");
  auto r = cli({"generate", "tiny", "-q", "-o", dir / "x.vdb"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("is a folder"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::is_directory(dir / "x.vdb"));
}

TEST(OutputSafety, FullDiskFailsWithTheReasonAndKeepsTheOldFile) {
  TempDir dir;
  ASSERT_EQ(cli({"generate", "tiny", "-q", "--seed", "3", "-o", dir / "cloud.vdb"}).run().code, 0);
  const std::string before = read_text(dir / "cloud.vdb");
  Process p = cli({"generate", "tiny", "-q", "-o", dir / "cloud.vdb"});
  p.fsize_limit = 20000;  // a "disk" that fills after 20 kB of any one file
  auto r = p.run();
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(dir / "cloud.vdb"), std::string::npos) << "names the destination, not a temporary: " << r.out;
  EXPECT_NE(r.out.find("File too large"), std::string::npos) << "the system's reason: " << r.out;
  EXPECT_EQ(r.out.find("Success"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(dir / "cloud.vdb"), before) << "the previous file must stay byte for byte";
  EXPECT_EQ(list_dir(dir.path), std::vector<std::string>{"cloud.vdb"}) << "no temporaries left";
}

TEST(OutputSafety, SeveralOutputsAreAllOrNothing) {
  TempDir dir;
  write_text(dir / "a.raw", "old raw");
  write_text(dir / "a.json", "old sidecar");
  // tiny's raw texture is 32^3 RGBA8 = 131072 bytes and its KTX2 the same texels plus a header:
  // a file-size limit between the two lets the raw files be staged and fails the KTX2.
  Process p = cli({"generate", "tiny", "-q", "-o", dir / "a.raw", "-o", dir / "b.ktx2"});
  p.fsize_limit = 131072 + 64;
  auto r = p.run();
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("b.ktx2"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(dir / "a.raw"), "old raw");
  EXPECT_EQ(read_text(dir / "a.json"), "old sidecar");
  EXPECT_EQ(list_dir(dir.path), (std::vector<std::string>{"a.json", "a.raw"}));
}

TEST(OutputSafety, AFailedRenameRestoresTheFilesAlreadyReplaced) {
  TempDir dir;
  fs::create_directory(dir / "d");
  fs::create_directory(dir / "e");
  write_text(dir / "d/x.txt", "old x");
  OutputBatch b;
  b.stage(dir / "d/x.txt", [](const std::string& tmp) { write_file_bytes(tmp, "new x", 5); });
  b.stage(dir / "e/y.txt", [](const std::string& tmp) { write_file_bytes(tmp, "new y", 5); });
  fs::remove(dir / "e");  // the anonymous temporary has no name, so the folder is empty and goes
  const std::string err = error_of([&] { b.commit(); });
  EXPECT_EQ(err.rfind("io: ", 0), 0u) << err;
  EXPECT_NE(err.find("y.txt"), std::string::npos) << err;
  EXPECT_EQ(read_text(dir / "d/x.txt"), "old x") << "the file replaced first is put back";
  EXPECT_EQ(list_dir(dir.path / "d"), std::vector<std::string>{"x.txt"});
}

TEST(OutputSafety, OutputsThatWouldOverwriteAnInputOrEachOtherAreRefusedUpFront) {
  TempDir dir;
  fs::copy_file(kPresets + "tiny.json", dir / "my.json");
  const std::string preset = read_text(dir / "my.json");
  auto r = cli({"generate", dir / "my.json", "-q", "-o", dir / "my.raw"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("overwrite the input preset"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(dir / "my.json"), preset);
  r = cli({"generate", "tiny", "-q", "-o", dir / "y.raw", "-o", dir / "y.exr"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("written twice"), std::string::npos) << r.out;
  r = cli({"generate", "tiny", "-q", "-o", dir / "z.vdb", "-o", dir / "./z.vdb"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_EQ(list_dir(dir.path), std::vector<std::string>{"my.json"}) << "nothing written";
  r = cli({"noise", "--size", "8", "-o", dir / "n.json"}).run();
  EXPECT_EQ(r.code, 1) << "the cube's sidecar would be the cube itself: " << r.out;
}

// Issue 47, D6-D9: no output of a run replaces a file the run reads, named by another path or a
// hard link included (cloudgen/input_scope.h).
TEST(OutputSafety, NoOutputReplacesAFileTheRunReads) {
  TempDir dir;
  fs::copy_file(kPresets + "tiny.json", dir / "x.json");
  const std::string preset = read_text(dir / "x.json");
  fs::create_hard_link(dir / "x.json", dir / "link.json");
  for (const std::string& out : {dir / "x.json", dir / "link.json"}) {
    auto r = cli({"plan", dir / "x.json", "--tiles", "2,1,1", "-o", out}).run();
    EXPECT_EQ(r.code, 1) << out << ": " << r.out;
    EXPECT_NE(r.out.find("overwrite the input preset"), std::string::npos) << r.out;
    EXPECT_EQ(read_text(dir / "x.json"), preset);
  }
  ASSERT_EQ(cli({"flowmap", "-q", "--size", "32x8", "-o", dir / "flow.png"}).run().code, 0);
  const std::string flow = read_text(dir / "flow.png");
  auto r = cli({"generate", "tiny", "-q", "--set", "motion.flow_map=" + (dir / "flow.png"), "-o", dir / "flow.png",
                "--format", "atlas-png"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("overwrite the flow map"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(dir / "flow.png"), flow);

  // merge: the merged file may be neither a tile nor the plan.
  ASSERT_EQ(cli({"plan", "tiny", "--tiles", "2,1,1", "-o", dir / "plan.json"}).run().code, 0);
  ASSERT_EQ(cli({"merge", dir / "plan.json", "--resume", "-q", "-o", dir / "whole.vdb"}).run().code, 0);
  const std::string plan = read_text(dir / "plan.json"), tile = read_text(dir / "tile_0000.vdb");
  fs::create_hard_link(dir / "tile_0000.vdb", dir / "same_tile.vdb");
  for (const std::string& out : {dir / "tile_0000.vdb", dir / "same_tile.vdb"}) {
    r = cli({"merge", dir / "plan.json", "-q", "-o", out}).run();
    EXPECT_EQ(r.code, 1) << out << ": " << r.out;
    EXPECT_NE(r.out.find("would overwrite"), std::string::npos) << r.out;
  }
  EXPECT_EQ(read_text(dir / "plan.json"), plan);
  EXPECT_EQ(read_text(dir / "tile_0000.vdb"), tile);
  r = cli({"merge", dir / "plan.json", "-q", "-o", dir / "again.vdb"}).run();
  EXPECT_EQ(r.code, 0) << "merge still records the checksums in its own plan: " << r.out;
}

TEST(OutputSafety, KilledRunsLeaveNoDebrisAndStaleTemporariesAreRemoved) {
  TempDir dir;
  Process p = cli({"generate", "tiny", "-q", "-o", dir / "c.vdb"});
  p.env = {"CLOUDGEN_TEST_HOLD=commit"};
  p.signal_on = "test hold at commit";
  p.sig = SIGKILL;
  auto r = p.run();
  EXPECT_EQ(r.term_signal, SIGKILL) << r.out;
  EXPECT_TRUE(list_dir(dir.path).empty()) << "a staged output is an anonymous file: nothing survives kill -9";
  // A named temporary of a dead process (as a filesystem without O_TMPFILE would leave).
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  const std::string stale = "." + std::string("c.vdb") + ".tmp-" + std::to_string(child) + "-0";
  write_text(dir / stale, "debris");
  write_text(dir / ".c.vdb.tmp-notapid-0", "not ours: kept");
  ASSERT_EQ(cli({"generate", "tiny", "-q", "-o", dir / "c.vdb"}).run().code, 0);
  EXPECT_EQ(list_dir(dir.path), (std::vector<std::string>{".c.vdb.tmp-notapid-0", "c.vdb"}));
}

TEST(OutputSafety, ReadOnlyFolderIsAnIoErrorExit2) {
  TempDir dir;
  fs::create_directory(dir / "ro");
  std::string out;
  int code;
  if (::geteuid() == 0) {
    // root ignores permission bits: use a read-only mount in a private mount namespace
    if (run_shell("unshare -m true") != 0) GTEST_SKIP() << "needs unshare for a read-only mount as root";
    code = run_shell("unshare -m sh -c 'mount -t tmpfs -o ro tmpfs " + (dir / "ro") + " && " + kCli +
                         " generate tiny -q -o " + (dir / "ro/x.vdb") + "'",
                     &out);
  } else {
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    code = run_cli("generate tiny -q -o " + (dir / "ro/x.vdb"), &out);
  }
  EXPECT_EQ(code, 2) << out;
  const bool reason = out.find("Read-only file system") != std::string::npos || out.find("Permission denied") != std::string::npos;
  EXPECT_TRUE(reason) << "the system's reason: " << out;
  EXPECT_EQ(out.find("internal error"), std::string::npos) << out;
}

// ---------------------------------------------------------------------------------------------
// Hostile inputs

TEST(HostileInputs, TruncatedAndTinyVdbFilesGiveOneClearLine) {
  TempDir dir;
  ASSERT_EQ(cli({"generate", "tiny", "-q", "-o", dir / "a.vdb"}).run().code, 0);
  const std::string bytes = read_text(dir / "a.vdb");
  for (size_t keep : {bytes.size() - 1, bytes.size() / 2, size_t(120), size_t(8), size_t(0)}) {
    SCOPED_TRACE(keep);
    write_text(dir / "t.vdb", bytes.substr(0, keep));
    for (const char* cmd : {"info"}) {
      auto r = cli({cmd, dir / "t.vdb"}).run();
      EXPECT_EQ(r.code, 1) << r.out.substr(0, 500);
      EXPECT_LT(r.out.size(), 600u) << "one clear line, not a flood";
      EXPECT_NE(r.out.find("t.vdb"), std::string::npos) << r.out.substr(0, 500);
    }
    EXPECT_EQ(error_of([&] { read_volume(dir / "t.vdb"); }).rfind("input: ", 0), 0u);
  }
}

// Issue 47, D4 and D5 (item 3): a VDB cloudgen wrote carries a seal (its UUID, from its bytes), so a
// changed byte anywhere is refused before OpenVDB reads it; any other VDB is read first in a child
// process under a memory limit, so a file that crashes OpenVDB's reader (D4: one byte made `info`
// abort with "malloc(): corrupted top size") or asks it for gigabytes (D5: a length of 0x7f7f7f7f
// took 2.1 GB) is refused with exit 1. The sweep damages the file at offsets across it.
TEST(HostileInputs, DamagedVdbsAreRefusedNotCrashedOn) {
  TempDir dir;
  ASSERT_EQ(cli({"generate", "tiny", "-q", "-o", dir / "r.vdb"}).run().code, 0);
  const std::string good = read_text(dir / "r.vdb");
  ASSERT_GT(good.size(), 10300u);
  ASSERT_EQ(good[21 + 14], '5') << "a sealed file";
  auto damaged = [&](size_t at, const std::string& bytes, bool unseal) {
    std::string d = good;
    d.replace(at, bytes.size(), bytes);
    if (unseal) d[21 + 14] = '4';  // as if another writer's random UUID: no seal to check
    write_text(dir / "d.vdb", d);
    return cli({"info", dir / "d.vdb"}).run();
  };
  auto r = damaged(10217, "\x04", true);  // D4
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("d.vdb: "), std::string::npos) << r.out;
  r = damaged(238, "\x7f\x7f\x7f\x7f", true);  // D5
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_EQ(r.out.find("internal error"), std::string::npos) << r.out;
  for (size_t at = 64; at + 4 < good.size(); at += good.size() / 9) {
    for (const std::string& bytes : {std::string("\x04"), std::string("\x7f\x7f\x7f\x7f")}) {
      r = damaged(at, bytes, false);
      if (good.compare(at, bytes.size(), bytes) == 0) continue;
      EXPECT_EQ(r.code, 1) << "sealed, byte " << at << ": " << r.out;
      EXPECT_TRUE(r.out.find("no longer match the seal") != std::string::npos ||
                  r.out.find("not a valid OpenVDB file") != std::string::npos)  // the layout walk, first
          << r.out;
      r = damaged(at, bytes, true);
      EXPECT_TRUE(r.code == 0 || r.code == 1) << "unsealed, byte " << at << ": " << r.code << " " << r.out;
      EXPECT_EQ(r.term_signal, 0) << r.out;
    }
  }
  write_text(dir / "d.vdb", good);
  EXPECT_EQ(cli({"info", dir / "d.vdb"}).run().code, 0);
}

TEST(HostileInputs, LevelSetsNonFiniteValuesAndEmptyGridsAreNamed) {
  TempDir dir;
  // Python's OpenVDB binding writes grids our writer never would.
  const std::string py =
      "import numpy as np, pyopenvdb as vdb, sys\n"
      "d = sys.argv[1]\n"
      "g = vdb.FloatGrid(); g.name = 'density'; g.gridClass = vdb.GridClass.LEVEL_SET\n"
      "g.copyFromArray(np.full((4, 4, 4), 0.5, dtype='float32')); vdb.write(d + '/ls.vdb', grids=[g])\n"
      "g = vdb.FloatGrid(); g.name = 'density'\n"
      "g.copyFromArray(np.full((4, 4, 4), 0.5, dtype='float32')); acc = g.getAccessor()\n"
      "acc.setValueOn((1, 1, 1), float('inf')); acc.setValueOn((2, 2, 2), float('nan'))\n"
      "vdb.write(d + '/inf.vdb', grids=[g])\n"
      "vdb.write(d + '/none.vdb', grids=[])\n";
  write_text(dir / "make.py", py);
  std::string out;
  if (run_shell("/usr/bin/python3 " + (dir / "make.py") + " " + dir.path.string(), &out) != 0)
    GTEST_SKIP() << "python3-openvdb unavailable: " << out;
  EXPECT_NE(error_of([&] { read_volume(dir / "ls.vdb"); }).find("level set"), std::string::npos);
  const std::string inf = error_of([&] { read_volume(dir / "inf.vdb"); });
  EXPECT_NE(inf.find("NaN or infinite"), std::string::npos) << inf;
  auto r = cli({"info", dir / "inf.vdb"}).run();
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("1 NaN and 1 infinite"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("max 0.5"), std::string::npos) << "min/max over finite values: " << r.out;
  r = cli({"info", dir / "none.vdb"}).run();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("no grids"), std::string::npos) << r.out;
}

// A 70 KB VDB whose density is one active 65536^3 region (4096 root tiles, no leaves) kept the CPU
// viewer busy for over a minute: the memory and work estimates counted the tiles as a few voxels
// (NanoVDB's own count takes a 4096^3 root tile for 32^3 voxels). Active voxels now count each
// tile as the voxels it covers, and the viewer refuses such a file at once, exit 1, naming it.
TEST(HostileInputs, AnActiveTileCountsAsTheVoxelsItCovers) {
  TempDir dir;
  const std::string py =
      "import pyopenvdb as vdb, sys\n"
      "d = sys.argv[1]\n"
      "g = vdb.FloatGrid(); g.name = 'density'\n"
      "g.fill((0, 0, 0), (65535, 65535, 65535), 0.5, True); vdb.write(d + '/region.vdb', grids=[g])\n"
      "g = vdb.FloatGrid(); g.name = 'density'\n"
      "g.fill((0, 0, 0), (4095, 4095, 4095), 0.5, True); g.getAccessor().setValueOn((5000, 0, 0), 0.25)\n"
      "vdb.write(d + '/tile.vdb', grids=[g])\n";
  write_text(dir / "make.py", py);
  std::string out;
  if (run_shell("/usr/bin/python3 " + (dir / "make.py") + " " + dir.path.string(), &out) != 0)
    GTEST_SKIP() << "python3-openvdb unavailable: " << out;
  EXPECT_LT(fs::file_size(dir / "region.vdb"), 100000u);
  EXPECT_EQ(nano_from_vdb(dir / "region.vdb").grids[0].active_voxels, uint64_t(1) << 48);
  // One root tile and one leaf voxel: 4096^3 + 1.
  EXPECT_EQ(nano_from_vdb(dir / "tile.vdb").grids[0].active_voxels, (uint64_t(1) << 36) + 1);
  // cloudgen's dense reader counts the box: refused by the read budget, not allocated.
  EXPECT_NE(error_of([&] { read_volume(dir / "region.vdb"); }).find("to load densely"), std::string::npos);
  Process v = cli({dir / "region.vdb", "--headless", "--backend", "cpu", "--size", "16x9", "--out", dir / "r.png"});
  v.program = std::string(CLOUD_BINARY_DIR) + "/bin/cloudviewer";
  if (!fs::exists(v.program)) return;
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = v.run();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("input '" + (dir / "region.vdb") + "': volume (NanoVDB grids): its active tiles cover 281474976710656 voxels"),
            std::string::npos)
      << r.out;
  EXPECT_LT(seconds, 30.0) << "refused from the estimate, before any work on the region";
  EXPECT_FALSE(fs::exists(dir / "r.png"));
}

TEST(HostileInputs, DeepAndDuplicateJsonIsRefusedWithThePointer) {
  // 100k nested arrays under a key of the wrong type: used to overflow the stack while printing.
  const std::string deep = "{\"threshold\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  const std::string e = error_of([&] { parse_preset(deep, "deep.json"); });
  EXPECT_NE(e.find("deep.json: /threshold"), std::string::npos) << e.substr(0, 300);
  EXPECT_NE(e.find("nested deeper than 64"), std::string::npos) << e.substr(0, 300);
  EXPECT_LT(e.size(), 600u);
  const std::string dup = error_of([] { parse_preset("{\"channels\": {\"r\": {\"octaves\": 3, \"octaves\": 5}}}", "d.json"); });
  EXPECT_NE(dup.find("d.json: /channels/r: duplicate key \"octaves\""), std::string::npos) << dup;
  EXPECT_NE(error_of([] { parse_preset("{}", "x.json", {"towers.list=" + std::string(200, '[') + std::string(200, ']')}); })
                .find("nested deeper"),
            std::string::npos);
  // A list index far beyond the end would make the JSON library allocate it (found by fuzz_cli).
  const std::string idx = error_of(
      [] { parse_preset(R"({"towers": {"list": [{}]}})", "x.json", {"towers.list.99999999999.amplitude=1"}); });
  EXPECT_NE(idx.find("is not an index of a list"), std::string::npos) << idx;
  EXPECT_NE(error_of([] { parse_preset("{}", "x.json", {"towers.list.99999999999=1"}); }).find("beyond the end of a new list"),
            std::string::npos);
  EXPECT_NO_THROW(parse_preset("{}", "x.json", {"towers.list.0.amplitude=0.25"}));
  TempDir dir;
  write_text(dir / "deep.json", deep);
  for (const char* cmd : {"validate", "generate"}) {
    Process p = cli({cmd, dir / "deep.json"});
    if (std::string(cmd) == "generate") p.args.insert(p.args.end(), {"-o", dir / "x.vdb"});
    auto r = p.run();
    EXPECT_EQ(r.code, 1) << cmd << ": " << r.out.substr(0, 300);
  }
}

TEST(HostileInputs, FlagsOutOfRangeAreRefusedWithTheRange) {
  TempDir dir;
  const std::string out = dir / "x.vdb";
  struct Case {
    std::vector<std::string> args;
    const char* expect;
  } cases[] = {
      {{"generate", "tiny", "--threads", "2147483647", "-o", out}, "not in range"},
      {{"generate", "tiny", "--threads", "100000000", "-o", out}, "not in range"},
      {{"generate", "tiny", "--threads", "-3", "-o", out}, "not in range"},
      {{"generate", "tiny", "--seed", "-1", "-o", out}, "--seed"},
      {{"generate", "tiny", "--seed", "9007199254740993", "-o", out}, "out of range"},
      {{"generate", "tiny", "--seed", "12abc", "-o", out}, "--seed"},
      {{"noise", "--seed", "-1", "--size", "8", "-o", dir / "n.raw"}, "--seed"},
      {{"noise", "--threads", "2147483647", "--size", "8", "-o", dir / "n.raw"}, "not in range"},
      {{"noise", "--period", "nan", "--size", "8", "-o", dir / "n.raw"}, "--period"},
      {{"generate", "tiny", "--region", "0,0,0:0,0,0", "-o", out}, "extent"},
      {{"generate", "tiny", "--region", "0,0,0:8,8,8junk", "-o", out}, "--region"},
      {{"generate", "tiny", "--region", "0,0,0:8,8,8,", "-o", out}, "--region"},
      {{"generate", "tiny", "--region", "30,0,0:8,8,8", "-o", out}, "reaches voxel 38"},
      {{"generate", "tiny", "--max-memory", "-5G", "-o", out}, "--max-memory"},
      {{"generate", "tiny", "--no-such-flag", "-o", out}, "no-such-flag"},
  };
  for (const Case& c : cases) {
    Process p = cli(c.args);
    auto r = p.run();
    std::string joined;
    for (auto& a : c.args) joined += a + " ";
    EXPECT_EQ(r.code, 1) << joined << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << joined << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(out));
  // The shared parsers, directly.
  EXPECT_EQ(parse_uint("9007199254740992", "--seed", kMaxSeed), kMaxSeed);
  const Region r = parse_region("1,2,3:4,5,6", {{10, 10, 10}});
  EXPECT_EQ(r.origin, (std::array<uint32_t, 3>{{1, 2, 3}}));
  EXPECT_EQ(r.extent, (std::array<uint32_t, 3>{{4, 5, 6}}));
  EXPECT_EQ(parse_bytes("2G", "--max-memory"), uint64_t(2) << 30);
  EXPECT_THROW(parse_number_list("1,inf,3", "--at", 3, 3), InputError);
}

TEST(HostileInputs, SidecarFieldsAreTypedAndSizesCannotOverflow) {
  Volume v;
  v.dims = {{2, 2, 2}};
  v.density.assign(8, 0.5f);
  const std::vector<uint8_t> texels = pack_texels(v, Texel::Rgba8);
  auto err = [&](const std::string& sidecar) { return error_of([&] { parse_raw(sidecar, texels, "t.raw"); }); };
  EXPECT_EQ(err(R"({"format": "rgba8", "size": [2, 2, 2]})"), "");
  struct Case {
    const char* sidecar;
    const char* expect;
  } cases[] = {
      {R"({"format": "rgba8", "size": [8589934594, 2, 2]})", "field \"size[0]\" is 8589934594"},  // 33 bits
      {R"({"format": "rgba8", "size": [65536, 65536, 65536]})", "2^34 voxels"},  // product overflows nothing, still refused
      {R"({"format": "rgba8", "size": ["2", 2, 2]})", "field \"size[0]\" should be an integer"},
      {R"({"format": "rgba8", "size": [2, 2]})", "field \"size\" should be an array of 3"},
      {R"({"format": 7, "size": [2, 2, 2]})", "field \"format\" should be a string"},
      {R"({"format": "rgba64", "size": [2, 2, 2]})", "is not a texel format"},
      {R"({"format": "rgba8", "size": [2, 2, 2], "voxel_size": 1e308})", "field \"voxel_size\" is"},
      {R"({"format": "rgba8", "size": [2, 2, 2], "origin": [0, "x", 0]})", "field \"origin[1]\""},
      {R"({"format": "rgba8", "size": [2, 2, 2], "tiles_xz": "yes"})", "field \"tiles_xz\""},
      {R"({"format": "rgba8", "size": [2, 2, 2], "channels": [1]})", "field \"channels\""},
      {R"({"format": "rgba8", "size": [2, 2, 2], "a": 1, "a": 2})", "duplicate key"},
      {R"({"format": "rgba8", "size": [4, 2, 2]})", "needs 64"},
  };
  for (const Case& c : cases) {
    const std::string e = err(c.sidecar);
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.sidecar << " -> " << e;
    EXPECT_EQ(e.rfind("input: t.", 0), 0u) << e;
  }
}

TEST(HostileInputs, Ktx2HeadersAreCheckedBeforeAnyAllocation) {
  Volume v;
  v.dims = {{2, 2, 2}};
  v.density.assign(8, 0.25f);
  TempDir dir;
  write_ktx2(v, dir / "t.ktx2", ExportOptions{});
  const std::string good = read_text(dir / "t.ktx2");
  auto with = [&](size_t off, uint64_t value, size_t width) {
    std::string b = good;
    std::memcpy(&b[off], &value, width);
    return error_of([&] { parse_ktx2(std::vector<uint8_t>(b.begin(), b.end()), "t.ktx2"); });
  };
  EXPECT_EQ(with(20, 2, 4), "");
  EXPECT_NE(with(20, 0x7fffffff, 4).find("pixelWidth 2147483647 is outside"), std::string::npos);
  EXPECT_NE(with(28, 0, 4).find("pixelDepth 0"), std::string::npos);
  EXPECT_NE(with(12, 12345, 4).find("vkFormat 12345"), std::string::npos);
  EXPECT_NE(with(88, ~uint64_t(0), 8).find("level 0"), std::string::npos);  // length past the end
  EXPECT_NE(with(80, ~uint64_t(0) - 4, 8).find("level 0"), std::string::npos);  // offset + length wraps
  EXPECT_NE(with(36, 6, 4).find("cube maps"), std::string::npos);
  // Round trip keeps what the writer wrote (issue 7: readers drop nothing).
  v.voxel_size = 12.5;
  v.origin = {{-100, 250, 3}};
  v.tiles_xz = true;
  v.metadata = {{"preset", "unit"}};
  write_ktx2(v, dir / "m.ktx2", ExportOptions{});
  Volume r = read_ktx2(dir / "m.ktx2");
  EXPECT_EQ(r.voxel_size, 12.5);
  EXPECT_EQ(r.origin, v.origin);
  EXPECT_TRUE(r.tiles_xz);
  ASSERT_EQ(r.metadata.size(), 1u);
  EXPECT_EQ(r.metadata[0].second, "unit");
}

TEST(HostileInputs, TheDenseBudgetIsCheckedBeforeAllocating) {
  Volume v;
  v.dims = {{4, 4, 4}};
  v.density.assign(64, 0.5f);
  TempDir dir;
  write_raw(v, dir / "s.raw", ExportOptions{});
  EXPECT_NO_THROW(read_volume(dir / "s.raw"));
  const std::string e = error_of([&] { read_volume(dir / "s.raw", 100); });
  EXPECT_NE(e.find("more than the"), std::string::npos) << e;
  // A sidecar claiming 4096^3 over a small file is refused for the size mismatch, never allocated.
  write_text(dir / "s.json", R"({"format": "rgba32f", "size": [2048, 2048, 2048]})");
  EXPECT_NE(error_of([&] { read_volume(dir / "s.raw"); }).find("needs"), std::string::npos);
}

TEST(HostileInputs, ControlCharactersArePrintedEscaped) {
  TempDir dir;
  write_text(dir / "evil.json", "{\"name\": \"x\\u001b[2J\\nerror: forged\", \"resolution\": [16, 16, 16]}");
  auto r = cli({"generate", dir / "evil.json", "-o", dir / "e.vdb"}).run();
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos) << "no raw escape sequence reaches the terminal";
  EXPECT_EQ(r.out.find("\nerror: forged"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\\x1b[2J\\x0aerror: forged"), std::string::npos) << r.out;
  r = cli({"info", dir / "e.vdb"}).run();
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos);
  EXPECT_EQ(printable("a\tb\x7f", true), "a\tb\\x7f");
}

// The exit codes of every exception type: ExitCodes.OneRuleForBothPrograms (test_viewer.cpp).
TEST(ExitCodes, MessagesEscapeControlCharacters) {
  try {
    throw InputError("bad\x1b value");
  } catch (...) {
    EXPECT_EQ(error_message_of(std::current_exception()), "error: bad\\x1b value");
  }
}

// ---------------------------------------------------------------------------------------------
// Every numeric preset key at the ends of its range and just beyond: generated values stay finite
// and in [0, 1], or the preset is refused up front.

TEST(StressTable, EveryPresetKeyAtAndBeyondTheEndsOfItsRange) {
  const std::string base = read_text(kPresets + "tiny.json");
  size_t generated = 0, refused = 0;
  for (const ParamInfo& pi : params()) {
    if (pi.type != "number" && pi.type != "integer" && pi.type != "period" && pi.type != "vec3" && pi.type != "ivec3" &&
        pi.type != "vec2")
      continue;
    if (pi.pointer.find('*') != std::string::npos) continue;  // list elements: covered by /towers/list cases below
    const auto lb = pi.range.find('['), comma = pi.range.find(", ", lb), rb = pi.range.find(']', comma);
    ASSERT_NE(rb, std::string::npos) << pi.pointer << " " << pi.range;
    const double lo = std::stod(pi.range.substr(lb + 1, comma - lb - 1)),
                 hi = std::stod(pi.range.substr(comma + 2, rb - comma - 2));
    const bool integer = pi.type == "integer" || pi.type == "ivec3" || pi.type == "period";
    const double step = integer ? 1 : std::max(1e-9, std::fabs(hi - lo) * 1e-6);
    std::string key = pi.pointer.substr(1);
    std::replace(key.begin(), key.end(), '/', '.');
    for (double value : {lo, hi, lo - step, hi + step}) {
      std::ostringstream val;
      val.precision(17);
      val << value;
      std::string v = val.str();
      if (pi.type == "vec3" || pi.type == "ivec3") v = "[" + v + "," + v + "," + v + "]";
      if (pi.type == "vec2") v = value == lo || value == lo - step ? "[" + v + ", 1]" : "[0, " + v + "]";
      const bool inside = value >= lo && value <= hi;
      SCOPED_TRACE(key + "=" + v);
      Preset p;
      try {
        p = parse_preset(base, "tiny.json", {key + "=" + v});
      } catch (const InputError& e) {
        // Beyond the range: always refused. Inside: refused only by a cross-check that names why.
        ++refused;
        if (inside) {
          EXPECT_EQ(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
        }
        continue;
      } catch (const noise3d::InvalidParameter&) {
        ++refused;
        continue;
      }
      EXPECT_TRUE(inside) << "accepted a value outside " << pi.range;
      if (key == "resolution" && value > 64) continue;  // parsed and accepted; too big to bake here
      const uint32_t longest = *std::max_element(p.resolution.begin(), p.resolution.end());
      if (longest > 24) rescale(p, 24);
      Volume vol = generate(p);
      size_t bad = 0;
      for (float f : vol.density) bad += !(f >= 0.0f && f <= 1.0f);
      for (const auto& d : vol.detail)
        for (float f : d) bad += !(f >= 0.0f && f <= 1.0f);
      EXPECT_EQ(bad, 0u) << "values outside [0, 1] or not finite";
      ++generated;
    }
  }
  std::cout << generated << " cases generated, " << refused << " refused up front\n";
  EXPECT_GT(generated, 50u);  // sanity: the table has ~60 numeric keys
  EXPECT_GT(refused, 50u);
}

// ---------------------------------------------------------------------------------------------
// Readers keep what writers wrote (issue 7)

TEST(RoundTrip, RawReadsTheOccupancyFileItWroteAndRefusesADamagedOne) {
  TempDir dir;
  Preset p = load_preset(kPresets + "tiny.json");
  Volume v = generate(p);
  ASSERT_FALSE(v.occupancy.empty());
  write_raw(v, dir / "t.raw", ExportOptions{});
  const std::string occ_path = dir / "t.occupancy.raw";
  std::string occ = read_text(occ_path);
  ASSERT_EQ(occ.size(), v.occupancy.size());
  EXPECT_EQ(std::vector<uint8_t>(occ.begin(), occ.end()), v.occupancy) << "the file holds the written grid";
  // Marking an empty cell occupied keeps the grid conservative: the reader must return the file's
  // grid as it is (it reads the file rather than rebuilding).
  const size_t empty = occ.find('\0');
  ASSERT_NE(empty, std::string::npos);
  occ[empty] = 1;
  write_text(occ_path, occ);
  Volume r = read_raw(dir / "t.raw");
  EXPECT_EQ(r.occupancy[empty], 1);
  EXPECT_EQ(r.occupancy_cell, v.occupancy_cell);
  EXPECT_EQ(r.occupancy_padding, v.occupancy_padding);
  // Clearing an occupied cell would hide cloud from the marcher: refused, naming the cell.
  std::string bad(occ.size(), '\0');
  write_text(occ_path, bad);
  const std::string e = error_of([&] { read_raw(dir / "t.raw"); });
  EXPECT_NE(e.find("marks cell"), std::string::npos) << e;
  // Without the file the grid is rebuilt from the density.
  fs::remove(occ_path);
  EXPECT_EQ(read_raw(dir / "t.raw").occupancy, v.occupancy);
}

// Every texel format through both texture files (.raw with its .json sidecar, .ktx2): the values
// within the format's rounding (rgba8 half a step, rgba16f 11 significant bits, rgba32f exact) and
// every other field of the volume exactly: placement, tiling, channel names, metadata, occupancy.
struct TextureCase {
  const char* texel;
  const char* ext;
};
class TextureRoundTrip : public ::testing::TestWithParam<TextureCase> {};
TEST_P(TextureRoundTrip, KeepsEveryFieldWithinTheTexelsRounding) {
  Volume v;
  v.dims = {{5, 3, 4}};
  v.voxel_size = 7.25;
  v.origin = {{-1000.5, 2500, 12}};
  v.tiles_xz = true;
  v.density.resize(v.voxel_count());
  v.detail[0].resize(v.voxel_count());
  v.detail[1].resize(v.voxel_count());
  for (size_t i = 0; i < v.density.size(); ++i) {
    v.density[i] = float(i % 7) / 6.0f;
    v.detail[0][i] = float(i % 5) / 4.0f;
    v.detail[1][i] = float((i * 7) % 11) / 10.0f;
  }
  v.detail_names = {{"erosion", "wisps", "detail_a"}};
  v.metadata = {{"preset", "unit test"}, {"seed", "42"}};
  build_occupancy(v);
  TempDir dir;
  ExportOptions o;
  const std::string texel = GetParam().texel, name = std::string("v") + GetParam().ext;
  o.texel = parse_texel(texel);
  const double tol = texel == "rgba8" ? 0.5 / 255 + 1e-7 : texel == "rgba16f" ? 1.0 / 2048 : 0.0;
  write_volume(v, dir / name, format_from_path(name), o);
  Volume r = read_volume(dir / name);
  ASSERT_EQ(r.dims, v.dims);
  double err = 0;
  for (size_t i = 0; i < v.voxel_count(); ++i)
    for (double d : {r.density[i] - v.density[i], r.detail[0][i] - v.detail[0][i], r.detail[1][i] - v.detail[1][i]})
      err = std::max(err, std::fabs(d));
  EXPECT_LE(err, tol);
  EXPECT_EQ(r.voxel_size, v.voxel_size);
  EXPECT_EQ(r.origin, v.origin);
  EXPECT_EQ(r.tiles_xz, v.tiles_xz);
  EXPECT_TRUE(r.detail[2].empty()) << "a channel that was not written stays absent";
  EXPECT_EQ(r.detail_names[0], "erosion");
  EXPECT_EQ(r.detail_names[1], "wisps");
  EXPECT_EQ(r.metadata, v.metadata);
  EXPECT_EQ(r.occupancy, v.occupancy);
  if (std::string(GetParam().ext) == ".raw") {
    EXPECT_TRUE(fs::exists(dir / "v.json"));
    EXPECT_TRUE(fs::exists(dir / "v.occupancy.raw"));
  }
}
INSTANTIATE_TEST_SUITE_P(EveryTexelAndFile, TextureRoundTrip,
                         ::testing::Values(TextureCase{"rgba8", ".raw"}, TextureCase{"rgba8", ".ktx2"},
                                           TextureCase{"rgba16f", ".raw"}, TextureCase{"rgba16f", ".ktx2"},
                                           TextureCase{"rgba32f", ".raw"}, TextureCase{"rgba32f", ".ktx2"}),
                         [](const ::testing::TestParamInfo<TextureCase>& i) {
                           return std::string(i.param.texel) + (i.param.ext[1] == 'r' ? "Raw" : "Ktx2");
                         });
