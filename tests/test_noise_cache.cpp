// Incremental regeneration (noise_cache.h): a generate() that takes its channel noise from a
// NoiseCache equals a cold generate() of the same preset byte for byte, whatever the edit; an
// edit of what is applied after the noise evaluates none, a change of a channel's noise
// parameters evaluates that channel again, and the noise the last run did not use is dropped.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/noise_cache.h"
#include "cloudgen/preset.h"
#include "test_util.h"

using namespace cloudgen;
using testutil::same_bytes;

namespace {

// cumulus at half its resolution (64x32x64, 4x2x4 bricks): three detail channels, towers,
// coverage; a second or so for the whole test.
Preset cumulus(std::vector<std::string> sets) {
  sets.insert(sets.begin(), {"resolution=[64,32,64]", "voxel_size=50"});
  return load_preset(testutil::kPresets + "cumulus.json", sets);
}

void expect_same_volume(const Volume& warm, const Volume& cold, const std::string& what) {
  EXPECT_TRUE(same_bytes(warm.density, cold.density)) << what << ": density";
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bytes(warm.detail[c], cold.detail[c])) << what << ": detail " << c;
  EXPECT_EQ(warm.occupancy, cold.occupancy) << what << ": occupancy";
  EXPECT_EQ(warm.metadata, cold.metadata) << what << ": metadata";
}

struct Generated {
  Volume v;
  GenerateStats stats;
};

Generated generate_with(const Preset& p, NoiseCache* cache, int threads = 0) {
  GenerateOptions o;
  o.noise_cache = cache;
  o.threads = threads;
  Generated r;
  r.v = generate(p, o, &r.stats);
  return r;
}

}  // namespace

TEST(NoiseCache, EditsRecombineTheKeptNoiseIntoTheColdBytes) {
  NoiseCache cache;
  const Generated first = generate_with(cumulus({}), &cache);
  EXPECT_EQ(first.stats.noise_cached, 0u);
  EXPECT_GT(first.stats.noise_evaluated, 0u);
  expect_same_volume(first.v, generate_with(cumulus({}), nullptr).v, "first run");
  EXPECT_GT(cache.bytes(), 0u);

  // Edits applied one after another, as cloudviewer --edit does; each compared with a cold run.
  // Raising the threshold needs no brick that was not evaluated; the others may need new ones
  // (the skipping bound moves), which are evaluated and kept.
  struct Edit {
    std::string set;
    bool evaluates_nothing;
  };
  const std::vector<Edit> edits = {{"threshold=0.42", true},
                                   {"density_scale=0.8", true},
                                   {"coverage.low=0.2", false},
                                   {"towers.amplitude=0.9", false},
                                   {"height.profile=stratus", false},
                                   {"channels.r.remap=[0.7,0.95]", false},
                                   {"threshold=0.3", false}};
  std::vector<std::string> sets;
  for (const Edit& e : edits) {
    sets.push_back(e.set);
    const Preset p = cumulus(sets);
    const Generated warm = generate_with(p, &cache, 1);  // another thread count than the cold run's
    expect_same_volume(warm.v, generate_with(p, nullptr, 2).v, e.set);
    EXPECT_GT(warm.stats.noise_cached, 0u) << e.set;
    if (e.evaluates_nothing) {
      EXPECT_EQ(warm.stats.noise_evaluated, 0u) << e.set;
    }
  }
  // The same preset again: everything it needs is kept.
  const Generated again = generate_with(cumulus(sets), &cache);
  EXPECT_EQ(again.stats.noise_evaluated, 0u);
  EXPECT_GT(again.stats.noise_cached, 0u);
}

TEST(NoiseCache, ANoiseParameterChangeEvaluatesAgainAndDropsTheOldNoise) {
  NoiseCache cache;
  generate_with(cumulus({}), &cache);
  // A detail channel's period: that channel's blocks are evaluated, the density's are kept.
  const Generated period = generate_with(cumulus({"channels.b.period=6"}), &cache);
  expect_same_volume(period.v, generate_with(cumulus({"channels.b.period=6"}), nullptr).v, "channels.b.period");
  EXPECT_GT(period.stats.noise_evaluated, 0u);
  EXPECT_GT(period.stats.noise_cached, 0u);
  // The seed changes every channel's noise: nothing is found, and the old seed's noise is gone.
  const Generated seed = generate_with(cumulus({"seed=7"}), &cache);
  expect_same_volume(seed.v, generate_with(cumulus({"seed=7"}), nullptr).v, "seed");
  EXPECT_EQ(seed.stats.noise_cached, 0u);
  EXPECT_GT(seed.stats.noise_evaluated, 0u);
  const Generated back = generate_with(cumulus({}), &cache);
  EXPECT_EQ(back.stats.noise_cached, 0u) << "the old seed's noise should have been dropped";
  expect_same_volume(back.v, generate_with(cumulus({}), nullptr).v, "seed back");
  // A resolution change keeps nothing either (the lattice positions move).
  const Generated res = generate_with(load_preset(testutil::kPresets + "cumulus.json", {"resolution=[48,32,48]"}), &cache);
  EXPECT_EQ(res.stats.noise_cached, 0u);
}

TEST(NoiseCache, RegionsAndSkipOffRunWithoutIt) {
  // A sub-box or skip_empty = false does not touch the cache (its slots are whole bricks of the
  // skipping run); the values are those of the plain run.
  NoiseCache cache;
  const Preset p = cumulus({});
  GenerateOptions o;
  o.noise_cache = &cache;
  o.region_origin = {16, 0, 16};
  o.region_extent = {32, 32, 16};
  GenerateStats st;
  GenerateOptions plain = o;
  plain.noise_cache = nullptr;
  const Volume v = generate(p, o, &st);
  EXPECT_EQ(st.noise_cached + st.noise_evaluated, 0u);
  EXPECT_EQ(cache.bytes(), 0u);
  EXPECT_TRUE(same_bytes(v.density, generate(p, plain).density));
}

TEST(NoiseCache, ShapeSourcesAndEditsOfThemKeepTheColdBytes) {
  // A preset with shape sources (their base density replaces profile, towers and coverage): the
  // shape kept per brick is reused by a threshold edit and dropped by an edit of a source.
  auto shaped = [](const std::vector<std::string>& sets) {
    Preset p = load_preset(testutil::kPresets + "cumulus-shaped.json", sets);
    rescale(p, 48);
    return p;
  };
  NoiseCache cache;
  generate_with(shaped({}), &cache);
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"threshold=0.25"}, {"threshold=0.25", "shape.falloff=150"}, {"density_scale=0.7"}}) {
    const Preset p = shaped(sets);
    const Generated warm = generate_with(p, &cache);
    expect_same_volume(warm.v, generate_with(p, nullptr).v, sets.back());
    EXPECT_GT(warm.stats.noise_cached, 0u) << sets.back();
  }
}
