// The window's authoring actions on a preset (issue 45 item 3), driven headless through the very
// functions the panel calls: Session::edit_preset, Session::save_preset_as, export_preset_files.
// A saved preset validates and regenerates the edited session's volume byte for byte; a failed or
// refused save leaves every file as it was; the shipped presets are never written; Export writes
// the bytes `cloudgen generate --set` writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../viewer/src/app/authoring.h"
#include "../viewer/src/app/session.h"
#include "cloudgen/errors.h"
#include "cloudgen/preset.h"
#include "cloudgen/preset_fields.h"
#include "cloudgen/preset_save.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/input.h"
#include "test_util_viewer.h"

using namespace cloudviewer;
namespace fs = std::filesystem;

namespace {

const std::string kTiny = testutil::kPresets + "tiny.json";

// tiny.json copied into `dir` (an input the test may own).
std::string own_copy(const testutil::TempDir& dir) {
  const std::string path = dir / "tiny.json";
  fs::copy_file(kTiny, path);
  return path;
}

}  // namespace

TEST(ViewerAuthoring, SavedPresetValidatesAndRegeneratesTheEditedVolume) {
  testutil::TempDir dir;
  const std::string input = own_copy(dir);
  RenderSettings s;
  Session session(input, s);
  const std::vector<float> before = session.volume().rgba;
  session.edit_preset("threshold=0.5");
  session.edit_preset("towers.list.0.amplitude=0.9");
  session.edit_preset("threshold=0.45");  // a dragged slider: the last value replaces the earlier
  EXPECT_THROW(session.edit_preset("threshold=5"), cloudgen::InputError);  // refused, and not kept
  ASSERT_EQ(session.preset().sets, (std::vector<std::string>{"towers.list.0.amplitude=0.9", "threshold=0.45"}));
  session.reopen(input, s);
  ASSERT_NE(session.volume().rgba, before) << "the edits changed nothing";

  const std::string saved = dir / "sub/edited.json";
  fs::create_directories(dir / "sub");
  session.save_preset_as(saved);
  std::string out;
  EXPECT_EQ(testutil::run_cli("validate " + saved, &out), 0) << out;
  EXPECT_EQ(open_input(saved, s).rgba, session.volume().rgba) << "the saved preset makes another volume";
  EXPECT_EQ(testutil::read_text(input), testutil::read_text(kTiny)) << "the input changed";
}

TEST(ViewerAuthoring, FailedOrRefusedSavesLeaveEveryFileAsItWas) {
  testutil::TempDir dir;
  const std::string input = own_copy(dir);
  const std::string old_file = dir / "old.json", old_text = "{\"name\": \"keep me\"}\n";
  testutil::write_text(old_file, old_text);
  // An edit the preset refuses: nothing replaces the old file.
  EXPECT_THROW(cloudgen::save_preset_as(input, {"threshold=5"}, old_file), cloudgen::InputError);
  EXPECT_EQ(testutil::read_text(old_file), old_text);
  // A folder, a path under a file, the input itself: refused or failed, nothing written.
  EXPECT_THROW(cloudgen::save_preset_as(input, {"threshold=0.4"}, dir.path.string()), cloudgen::InputError);
  EXPECT_THROW(cloudgen::save_preset_as(input, {"threshold=0.4"}, old_file + "/x.json"), cloudgen::Error);
  EXPECT_EQ(testutil::read_text(old_file), old_text);
  EXPECT_THROW(cloudgen::save_preset_as(input, {"threshold=0.4"}, input), cloudgen::InputError);
  EXPECT_EQ(testutil::read_text(input), testutil::read_text(kTiny));
  // Asked for, the input is replaced, and reads back with the edit.
  cloudgen::save_preset_as(input, {"threshold=0.4"}, input, true);
  EXPECT_NE(testutil::read_text(input).find("\"threshold\": 0.4"), std::string::npos) << testutil::read_text(input);
  // The shipped presets: never written, neither a new file nor an existing one (asked or not).
  const std::string shipped = cloudgen::shipped_preset_dir();
  const std::string tiny_text = testutil::read_text(kTiny);
  EXPECT_THROW(cloudgen::save_preset_as(input, {}, shipped + "/zz_test_new.json"), cloudgen::InputError);
  EXPECT_FALSE(fs::exists(shipped + "/zz_test_new.json"));
  EXPECT_THROW(cloudgen::save_preset_as(kTiny, {"threshold=0.4"}, kTiny, true), cloudgen::InputError);
  try {
    cloudgen::save_preset_as(input, {}, shipped + "/tiny.json");
  } catch (const cloudgen::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shipped presets"), std::string::npos) << e.what();
  }
  EXPECT_EQ(testutil::read_text(kTiny), tiny_text);
}

TEST(ViewerAuthoring, ExportWritesWhatCloudgenGenerateWrites) {
  testutil::TempDir dir;
  const std::string input = own_copy(dir);
  RenderSettings s;
  Session session(input, s);
  session.edit_preset("threshold=0.45");
  double last = -1;
  const std::vector<std::string> written =
      export_preset_files(session.input(), session.preset().sets, {dir / "panel.vdb"}, [&](double f) { last = f; });
  ASSERT_EQ(written, std::vector<std::string>{dir / "panel.vdb"});
  EXPECT_EQ(last, 1.0) << "the progress never reached the end";
  std::string out;
  ASSERT_EQ(testutil::run_cli("generate " + input + " --set threshold=0.45 -q -o " + (dir / "cli.vdb"), &out), 0) << out;
  const std::string a = testutil::read_text(dir / "panel.vdb");
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, testutil::read_text(dir / "cli.vdb")) << "Export and cloudgen generate wrote different bytes";
  // An export over its own input is refused before any work.
  EXPECT_THROW(export_preset_files(input, {}, {input}), cloudgen::InputError);
}

// Open in Blender: `cloudgen blender` of the exported VDB makes the .blend whose path it returns; a
// missing VDB fails with cloudgen's message. (Debian's blender: about 4 s; skipped without it.)
TEST(ViewerAuthoring, OpenInBlenderMakesTheSceneOfTheExportedVolume) {
  testutil::TempDir dir;
  const std::string input = own_copy(dir);
  try {
    open_in_blender(dir / "missing.vdb", dir / "missing.blend");
    ADD_FAILURE() << "a missing VDB was accepted";
  } catch (const cloudgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.vdb"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "missing.blend"));
  if (testutil::run_shell("command -v blender >/dev/null") != 0) GTEST_SKIP() << "no blender on the PATH";
  export_preset_files(input, {"threshold=0.45"}, {dir / "cloud.vdb"});
  EXPECT_EQ(open_in_blender(dir / "cloud.vdb", dir / "cloud.blend"), dir / "cloud.blend");
  EXPECT_GT(fs::file_size(dir / "cloud.blend"), 1000u);
}

// The panel's preset fields: every key of the preset table without a list index has a value (the
// file's, an edit's, else the table's default) and a group; an edit shows in them.
TEST(ViewerAuthoring, PanelShowsEveryPresetFieldWithItsValue) {
  const std::map<std::string, std::string> v = cloudgen::preset_values(kTiny, {"threshold=0.45", "coverage.low=0.2"});
  size_t plain = 0;
  for (const cloudgen::PresetField& f : cloudgen::preset_fields()) {
    EXPECT_NE(f.place.group, cloudgen::ParamGroup::Unset) << f.key;
    if (f.key.find('*') != std::string::npos) continue;
    ++plain;
    ASSERT_EQ(v.count(f.key), 1u) << f.key;
  }
  // Any other key is a list element's, its index in place of the table's "*".
  std::set<std::string> table;
  for (const cloudgen::PresetField& f : cloudgen::preset_fields()) table.insert(f.key);
  for (const auto& kv : v) {
    if (table.count(kv.first)) continue;
    std::string pattern = kv.first;
    const size_t dot = pattern.find_first_of("0123456789");
    ASSERT_NE(dot, std::string::npos) << kv.first;
    pattern.replace(dot, pattern.find('.', dot) - dot, "*");
    EXPECT_EQ(table.count(pattern), 1u) << kv.first;
  }
  EXPECT_GE(v.size(), plain);
  EXPECT_EQ(v.at("threshold"), "0.45");
  EXPECT_EQ(v.at("coverage.low"), "0.2");
  EXPECT_EQ(v.at("seed"), "3");                                      // the file's
  EXPECT_EQ(v.at("density_scale"), "1.0");                            // the table's default
  EXPECT_EQ(v.at("name"), "\"tiny\"");
}

// A list's elements (shape sources, towers) are on the panel too: one key per element and field,
// the element's value or the table's default ("null" where the key does not apply to its kind),
// and an edit of one element's key reaches it through the same --set path.
TEST(ViewerAuthoring, PanelShowsEachListElement) {
  const std::string congestus = testutil::kPresets + "cumulus-congestus.json";
  const std::map<std::string, std::string> v = cloudgen::preset_values(congestus, {"shape.sources.3.radius=400"});
  EXPECT_EQ(v.at("shape.sources.0.kind"), "\"ellipsoid\"");
  EXPECT_EQ(v.at("shape.sources.0.radii"), "[780,420,720]");
  EXPECT_EQ(v.at("shape.sources.0.radius"), "null");  // not a key of an ellipsoid: the panel skips it
  EXPECT_EQ(v.at("shape.sources.3.radius"), "400");    // the edit
  EXPECT_EQ(v.at("shape.sources.6.radius"), "260");
  EXPECT_EQ(v.at("shape.sources.2.rotate"), "[0,0,-8]");
  EXPECT_EQ(v.at("shape.sources.1.scale"), "[1, 1, 1]");  // the table's default
  EXPECT_EQ(v.count("shape.sources.7.kind"), 0u);          // seven sources, no eighth
  EXPECT_EQ(v.count("shape.sources.*.kind"), 0u);
  const cloudgen::Preset p = cloudgen::load_preset(congestus, {"shape.sources.3.radius=400"});
  ASSERT_EQ(p.shape.sources.size(), 7u);
  EXPECT_EQ(*p.shape.sources[3].radius, 400);
  // The panel's Add and Remove edit the whole list, from the list's own value (edits included):
  // a copy of the last element appended, element 1 removed.
  nlohmann::json list = nlohmann::json::parse(v.at("shape.sources"));
  ASSERT_EQ(list.size(), 7u);
  EXPECT_EQ(list[3]["radius"], 400);
  list.push_back(list.back());
  list.erase(list.begin() + 1);
  const std::vector<std::string> sets = {"shape.sources.3.radius=400", "shape.sources=" + list.dump()};
  const std::map<std::string, std::string> w = cloudgen::preset_values(congestus, sets);
  EXPECT_EQ(w.count("shape.sources.6.kind"), 1u);
  EXPECT_EQ(w.count("shape.sources.7.kind"), 0u);
  EXPECT_EQ(w.at("shape.sources.2.radius"), "400");  // the edited sphere, moved up by one
  EXPECT_EQ(w.at("shape.sources.6.radius"), w.at("shape.sources.5.radius"));
  EXPECT_EQ(cloudgen::load_preset(congestus, sets).shape.sources.size(), 7u);
}
