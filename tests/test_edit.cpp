// cloudviewer --edit (issue 45 item 2): a preset generated once, edited one key after another from
// the kept noise, renders the image of a fresh --set of the same keys bit for bit; --set takes the
// preset's own keys for a preset INPUT; bad edits and misplaced preset keys fail with exit 1 and
// a message naming the key, the value and what is allowed.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "test_util_viewer.h"

using testutil::run;

namespace {

const std::string kCumulus = testutil::kPresets + "cumulus.json";
// cumulus at half its resolution and a small frame: a few seconds for the whole file.
const std::vector<std::string> kSmall = {"--headless", "--size", "160x90", "--set", "resolution=[64,32,64]",
                                         "--set", "voxel_size=50"};

std::vector<std::string> args(std::vector<std::string> a) {
  a.insert(a.begin(), kCumulus);
  a.insert(a.end(), kSmall.begin(), kSmall.end());
  return a;
}

}  // namespace

TEST(ViewerEdit, EditsRenderTheImageOfAFreshSet) {
  testutil::TempDir dir;
  std::string out, err;
  ASSERT_EQ(run(args({"--edit", "threshold=0.4", "--edit", "density_scale=0.8", "--edit", "coverage.low=0.25",
                      "--stats", "--out", dir / "edit.png"}),
                &err, &out),
            0)
      << err;
  EXPECT_NE(out.find("edit 1/3 threshold=0.4: regenerated in "), std::string::npos) << out;
  EXPECT_NE(out.find("edit 3/3 coverage.low=0.25: regenerated in "), std::string::npos) << out;
  EXPECT_NE(out.find("noise boxes "), std::string::npos) << out;  // --stats: where the time went
  ASSERT_EQ(run(args({"--set", "threshold=0.4", "--set", "density_scale=0.8", "--set", "coverage.low=0.25", "--out",
                      dir / "set.png"}),
                &err),
            0)
      << err;
  ASSERT_EQ(run(args({"--out", dir / "plain.png"}), &err), 0) << err;
  const std::string edited = testutil::read_text(dir / "edit.png");
  ASSERT_FALSE(edited.empty());
  EXPECT_EQ(edited, testutil::read_text(dir / "set.png")) << "--edit and --set of the same keys differ";
  EXPECT_NE(edited, testutil::read_text(dir / "plain.png")) << "the edits changed nothing";
}

TEST(ViewerEdit, BadEditsAndMisplacedPresetKeysFailClearly) {
  testutil::TempDir dir;
  const std::string png = dir / "x.png";
  std::string err;
  // A value out of range: the key, the value and the range.
  EXPECT_EQ(run(args({"--edit", "threshold=5", "--out", png}), &err), 1);
  EXPECT_NE(err.find("--edit threshold=5"), std::string::npos) << err;
  EXPECT_NE(err.find("/threshold"), std::string::npos) << err;
  EXPECT_NE(err.find("range"), std::string::npos) << err;
  // An unknown preset key: the preset reader's did-you-mean.
  EXPECT_EQ(run(args({"--edit", "threshhold=0.4", "--out", png}), &err), 1);
  EXPECT_NE(err.find("did you mean \"threshold\""), std::string::npos) << err;
  // A render key is not an edit; an edit needs --headless and a preset.
  EXPECT_EQ(run(args({"--edit", "render.exposure=2", "--out", png}), &err), 1);
  EXPECT_NE(err.find("not a preset key"), std::string::npos) << err;
  EXPECT_EQ(run({"synthetic:sphere", "--headless", "--edit", "threshold=0.4", "--out", png}, &err), 1);
  EXPECT_NE(err.find("not a preset"), std::string::npos) << err;
  // A preset key with an input that is not a preset.
  EXPECT_EQ(run({"synthetic:sphere", "--headless", "--set", "threshold=0.4", "--out", png}, &err), 1);
  EXPECT_NE(err.find("--set threshold=0.4: a preset key"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(png));
}
