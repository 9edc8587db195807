// Painted weather maps (cloudgen/weather_map.h, coverage.kind "image"): the weather-map output of a
// noise-coverage preset fed back gives the same clouds, the channels mean what docs/shaping.md
// says (coverage, cloud type, top; grey = coverage only), the lookup wraps or clamps, skipping stays
// exact, thread counts give the same bytes, and bad files are refused naming the file, the field
// and what is allowed, through the library and the CLI, with nothing written.
#include <gtest/gtest.h>
#include <png.h>

#include <zlib.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/output.h"
#include "cloudgen/preset.h"
#include "cloudgen/weather_map.h"
#include "test_util.h"

using namespace cloudgen;

namespace {

using testutil::run_cli;
using testutil::same_bytes;
using testutil::TempDir;

/// A PNG written with libpng's low-level writer, so that any depth and colour type can be made:
/// `rows` holds height rows of packed samples as PNG stores them (16-bit big-endian).
void write_png(const std::string& path, uint32_t w, uint32_t h, int depth, int color, const std::vector<uint8_t>& data) {
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_TRUE(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    FAIL() << "libpng could not write " << path;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, depth, color, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (color == PNG_COLOR_TYPE_PALETTE) {
    png_color pal[2] = {{0, 0, 0}, {255, 255, 255}};
    png_set_PLTE(png, info, pal, 2);
  }
  png_write_info(png, info);
  const size_t row = data.size() / h;
  for (uint32_t j = 0; j < h; ++j) png_write_row(png, data.data() + j * row);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
}

/// A preset of 64 x 32 x 64 voxels painted with `file`; `neutral` makes the noise R exactly 1
/// (remap [-1, -0.5] sends every value to 1).
Preset painted(const std::string& file, bool tiling, bool neutral, const std::string& extra = "") {
  std::string j = R"({"resolution": [64, 32, 64], "voxel_size": 20, "height": {"profile": "cumulus"},
      "coverage": {"enabled": true, "kind": "image", "file": ")" + file + R"("}, "tiling": )" + (tiling ? "true" : "false");
  if (neutral) j += R"(, "threshold": 0.1, "channels": {"r": {"remap": [-1, -0.5]}})";
  return parse_preset(j + extra + "}", "/nowhere/painted.json");
}

/// A w x h map with coverage, type and top from f(i, j) -> {c, g, b}.
template <class F>
WeatherColumns columns(uint32_t w, uint32_t h, F f) {
  WeatherColumns c;
  c.w = w, c.h = h;
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      const std::array<float, 3> v = f(i, j);
      c.coverage.push_back(v[0]), c.type.push_back(v[1]), c.top.push_back(v[2]);
    }
  return c;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

struct Agreement {
  double max_diff = 0, iou = 0;
  size_t only_one = 0;  ///< voxels with density > 0 in one volume only
};

Agreement compare(const Volume& a, const Volume& b) {
  Agreement r;
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < a.density.size(); ++i) {
    r.max_diff = std::max(r.max_diff, double(std::abs(a.density[i] - b.density[i])));
    const bool x = a.density[i] > 0, y = b.density[i] > 0;
    inter += x && y, uni += x || y;
  }
  r.only_one = uni - inter;
  r.iou = uni ? double(inter) / uni : 1.0;
  return r;
}

}  // namespace

// The map of a noise-coverage preset, one texel per voxel column, fed back as coverage.kind
// "image": 16-bit quantisation moves coverage by at most 1 / 131070 and the cumulus type by
// 0.5 / 65535, so density moves by at most about density_scale / (1 - t) * 2e-5 < 1e-4.
TEST(WeatherMap, RoundTripReproducesTheDensity) {
  TempDir dir;
  for (const char* name : {"cumulus-field", "cumulonimbus", "stratus"}) {
    SCOPED_TRACE(name);
    const Preset p = load_preset(testutil::kPresets + name + ".json", {"resolution=[96,32,80]", "coverage.enabled=true"});
    const std::string map = dir / (std::string(name) + ".png");
    write_weather_map_png(map, weather_columns(p, 96, 80));
    const Preset q = load_preset(testutil::kPresets + name + ".json",
                                 {"resolution=[96,32,80]", "coverage.enabled=true", "coverage.kind=image", "coverage.file=" + map});
    ASSERT_TRUE(q.weather_map);
    EXPECT_EQ(q.weather_map->channels, 3);
    GenerateOptions o;
    o.detail = false;
    const Volume a = generate(p, o), b = generate(q, o);
    const Agreement g = compare(a, b);
    std::printf("  %s, 96x80 map: max |density difference| %.3g, IoU of density > 0 %.6f (%zu of %zu voxels differ)\n",
                name, g.max_diff, g.iou, g.only_one, a.density.size());
    EXPECT_LT(g.max_diff, 1e-4);
    EXPECT_GE(g.iou, 0.99);
    EXPECT_NE(preset_hash(p), preset_hash(q));
  }
  // A coarser map (48 x 40 for 96 x 80 columns) is filtered bilinearly: the cloud mostly stays where
  // it was, but cumulus-field's steep coverage edges (smoothstep over noise 0.56..0.66, about 16
  // columns a period here) are blurred: IoU 0.70 when written.
  const Preset p = load_preset(testutil::kPresets + "cumulus-field.json", {"resolution=[96,32,80]"});
  write_weather_map_png(dir / "half.png", weather_columns(p, 48, 40));
  const Preset q = load_preset(testutil::kPresets + "cumulus-field.json",
                               {"resolution=[96,32,80]", "coverage.kind=image", "coverage.file=" + (dir / "half.png")});
  GenerateOptions o;
  o.detail = false;
  const Agreement g = compare(generate(p, o), generate(q, o));
  std::printf("  cumulus-field, 48x40 map: max |density difference| %.3g, IoU %.4f\n", g.max_diff, g.iou);
  EXPECT_GE(g.iou, 0.6);
}

// R scales the profile, G picks the cloud-type gradient (cloud_type.glsl), B squeezes it below
// B * height: with R = 1 and a uniform map every voxel is the formula, exactly.
TEST(WeatherMap, ChannelsAreCoverageTypeAndTop) {
  TempDir dir;
  write_weather_map_png(dir / "u.png", columns(64, 64, [](uint32_t, uint32_t) { return std::array<float, 3>{0.8f, 1.0f, 0.5f}; }));
  const Preset p = painted(dir / "u.png", true, true);
  const WeatherColumns c = weather_columns(p, 64, 64);
  ASSERT_TRUE(c.typed);
  const float cov = float(52428 / 65535.0), top = float(32768 / 65535.0);
  EXPECT_EQ(c.coverage[100], cov);
  EXPECT_EQ(c.type[100], 1.0f);
  EXPECT_EQ(c.top[100], top);
  const Volume v = generate(p);
  size_t above = 0, below = 0;
  for (uint32_t y = 0; y < 32; ++y) {
    const double hn = (y + 0.5) / 32, hs = hn / double(top);
    const float prof = hs < 1 ? float(cloud_type_height_gradient(hs, 1.0)) : 0.0f;
    const float want = std::clamp((prof * cov - 0.1f) * float(1.0 / (1.0 - 0.1)), 0.0f, 1.0f);
    for (uint32_t x : {0u, 17u, 63u}) EXPECT_EQ(v.density[v.index(x, y, 40)], want) << "y " << y;
    (hs < 1 ? below : above) += v.density[v.index(5, y, 5)] > 0;
  }
  EXPECT_EQ(above, 0u);
  EXPECT_GT(below, 8u);
  // A grey map of 1 is the coverage-free preset, byte for byte (type and top from the profile).
  std::vector<uint8_t> ones(64 * 64, 255);
  write_png(dir / "g.png", 64, 64, 8, PNG_COLOR_TYPE_GRAY, ones);
  const Preset grey = painted(dir / "g.png", true, false);
  EXPECT_EQ(grey.weather_map->channels, 1);
  Preset plain = grey;
  plain.coverage_enabled = false;
  EXPECT_TRUE(same_bytes(generate(grey).density, generate(plain).density));
}

// Texel centres sit at ((i + 0.5) / width, (j + 0.5) / height) of the x-z extent: a 2-texel map
// [0, 1] read at the first column (u = 1/128) wraps to 0.5 - 1/64 when tiling, clamps to 0 otherwise.
TEST(WeatherMap, BilinearLookupWrapsWhenTilingAndClampsOtherwise) {
  TempDir dir;
  write_png(dir / "two.png", 2, 1, 8, PNG_COLOR_TYPE_GRAY, {0, 255});
  const WeatherColumns wrap = weather_columns(painted(dir / "two.png", true, false), 64, 4);
  const WeatherColumns clamp = weather_columns(painted(dir / "two.png", false, false), 64, 4);
  EXPECT_NEAR(wrap.coverage[0], 0.5 - 1.0 / 64, 1e-6);
  EXPECT_NEAR(wrap.coverage[63], 0.5 + 1.0 / 64, 1e-6);
  EXPECT_EQ(clamp.coverage[0], 0.0f);
  EXPECT_EQ(clamp.coverage[63], 1.0f);
  EXPECT_NEAR(clamp.coverage[32], 0.515625, 1e-6);  // u = 65/128: x = 2u - 0.5 = 0.515625
}

// Skipping never changes a byte, and skips the bricks of zero coverage and those above the tops;
// with towers (per-voxel bound) too. Thread counts give the same bytes.
TEST(WeatherMap, SkippingIsExactAndThreadCountsGiveTheSameBytes) {
  TempDir dir;
  // Cloud in a disc of radius 20 texels; tops 0.4 on the left half, 1 on the right; type along z.
  write_weather_map_png(dir / "m.png", columns(64, 64, [](uint32_t i, uint32_t j) {
                          const double r = std::hypot(i + 0.5 - 32, j + 0.5 - 32);
                          return std::array<float, 3>{r < 20 ? 1.0f : 0.0f, float(j) / 63, i < 32 ? 0.4f : 1.0f};
                        }));
  for (const std::string& extra : {std::string(), std::string(R"(, "towers": {"count": 2, "sigma": [0.1, 0.2, 0.1]})")}) {
    for (bool tiling : {true, false}) {
      SCOPED_TRACE(extra + (tiling ? " tiling" : " not tiling"));
      const Preset p = painted(dir / "m.png", tiling, false, extra);
      GenerateOptions on, off, one;
      off.skip_empty = false, one.threads = 1;
      GenerateStats s_on, s_off;
      const Volume a = generate(p, on, &s_on), b = generate(p, off, &s_off), c = generate(p, one);
      EXPECT_TRUE(same_bytes(a.density, b.density));
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bytes(a.detail[k], b.detail[k])) << "channel " << k;
      EXPECT_TRUE(same_bytes(a.density, c.density));
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bytes(a.detail[k], c.detail[k])) << "channel " << k;
      EXPECT_GT(s_on.active_voxels, 0u);
      EXPECT_GE(s_on.bricks_skipped, 2u) << "the four corner columns of bricks hold no coverage";
      EXPECT_EQ(s_off.bricks_skipped, 0u);
    }
  }
  // Above the tops: a uniform top of 0.2 leaves the upper bricks (y >= 16 of 32) empty and skipped.
  write_weather_map_png(dir / "low.png", columns(64, 64, [](uint32_t, uint32_t) { return std::array<float, 3>{1, 0.5, 0.2f}; }));
  GenerateStats st;
  const Volume v = generate(painted(dir / "low.png", true, false), {}, &st);
  EXPECT_GE(st.bricks_skipped, st.bricks / 2);
  EXPECT_GT(st.active_voxels, 0u);
  EXPECT_EQ(v.density[v.index(0, 31, 0)], 0.0f);
}

TEST(WeatherMap, PresetsWithoutAnImageKeepTheirHash) {
  const Preset a = load_preset(testutil::kPresets + "cumulus-field.json");
  const Preset b = load_preset(testutil::kPresets + "cumulus-field.json", {"coverage.file=unused.png"});
  EXPECT_EQ(preset_hash(a), preset_hash(b));
  EXPECT_FALSE(b.weather_map);
}

// Each bad file: InputError naming the field, the file and what is allowed.
TEST(WeatherMap, BadFilesNameTheFileTheFieldAndWhatIsAllowed) {
  TempDir dir;
  const std::string allowed = "8- or 16-bit grey, RGB or RGBA PNG";
  write_weather_map_png(dir / "ok.png", columns(8, 8, [](uint32_t, uint32_t) { return std::array<float, 3>{1, 1, 1}; }));
  std::vector<uint8_t> ok = read_file_bytes(dir / "ok.png");
  testutil::write_text(dir / "empty.png", "");
  testutil::write_text(dir / "text.png", "not a png at all");
  testutil::write_text(dir / "cut.png", std::string(ok.begin(), ok.begin() + ok.size() / 2));
  write_png(dir / "onebit.png", 8, 1, 1, PNG_COLOR_TYPE_GRAY, {0xf0});
  write_png(dir / "palette.png", 8, 1, 8, PNG_COLOR_TYPE_PALETTE, std::vector<uint8_t>(8, 1));
  write_png(dir / "huge.png", 5000, 1, 8, PNG_COLOR_TYPE_GRAY, std::vector<uint8_t>(5000, 9));
  struct Case {
    std::string file, expect;
  };
  const std::vector<Case> cases = {
      {"missing.png", "no such file"},
      {"empty.png", "the file is empty (0 bytes); a weather map is an " + allowed},
      {"text.png", "not a PNG file; a weather map is an " + allowed},
      {"cut.png", "the file ends early (truncated PNG); a weather map is an " + allowed},
      {"onebit.png", "1-bit samples; a weather map is an " + allowed},
      {"palette.png", "a palette image; a weather map is an " + allowed},
      {"huge.png", "5000 x 1 texels; a weather map may have at most 4096 a side"},
  };
  for (const Case& c : cases) {
    const std::string e = error_of([&] { painted(dir / c.file, true, false); });
    EXPECT_NE(e.find("/nowhere/painted.json: /coverage/file: coverage.file " + (dir / c.file) + ": " + c.expect),
              std::string::npos)
        << c.file << "\n got: " << e;
  }
  // A zero width in the header (CRC made right): libpng's own words, with the file and the field.
  std::vector<uint8_t> zero = ok;
  for (int k = 16; k < 20; ++k) zero[size_t(k)] = 0;  // IHDR width
  const unsigned long crc = crc32(crc32(0, nullptr, 0), zero.data() + 12, 17);
  for (int k = 0; k < 4; ++k) zero[size_t(29 + k)] = uint8_t(crc >> (24 - 8 * k));
  const std::string e = error_of([&] { read_weather_map_png(zero.data(), zero.size(), "z.png"); });
  EXPECT_NE(e.find("coverage.file z.png: "), std::string::npos) << e;
  EXPECT_NE(e.find(allowed), std::string::npos) << e;
  // The keys: image needs coverage.enabled and a file.
  EXPECT_NE(error_of([] { parse_preset(R"({"coverage": {"kind": "image", "file": "x.png"}})", "k.json"); })
                .find("k.json: /coverage/enabled: coverage.kind \"image\" needs coverage.enabled true"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_preset(R"({"coverage": {"enabled": true, "kind": "image"}})", "k.json"); })
                .find("k.json: /coverage/file: coverage.kind \"image\" needs a PNG file"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_preset(R"({"coverage": {"kind": "picture"}})", "k.json"); })
                .find("perlin | worley | perlin-worley | image"),
            std::string::npos);
}

// The CLI: weather-map writes the map generate reads back; bad files exit 1 and write nothing;
// the map never replaces an input.
TEST(WeatherMap, CliWritesTheMapAndRefusesBadInput) {
  TempDir dir;
  std::string out;
  testutil::write_text(dir / "p.json", R"({"resolution": [40, 16, 24], "voxel_size": 50, "height": {"profile": "stratus"},
      "coverage": {"enabled": true, "period": 3}})");
  ASSERT_EQ(run_cli("weather-map " + (dir / "p.json") + " -o " + (dir / "w.png"), &out), 0) << out;
  const auto m = load_weather_map(dir / "w.png");
  EXPECT_EQ(m->width, 40);
  EXPECT_EQ(m->height, 24);
  EXPECT_EQ(m->channels, 3);
  const WeatherColumns c = weather_columns(load_preset(dir / "p.json"), 40, 24);
  for (size_t k = 0; k < c.coverage.size(); ++k) {
    ASSERT_NEAR(m->texels[3 * k], c.coverage[k], 0.5 / 65535 + 1e-7);
    ASSERT_EQ(m->texels[3 * k + 1], 0.0f) << "stratus";
    ASSERT_EQ(m->texels[3 * k + 2], 1.0f);
  }
  ASSERT_EQ(run_cli("weather-map " + (dir / "p.json") + " --size 20 -q -o " + (dir / "s.png"), &out), 0) << out;
  EXPECT_EQ(load_weather_map(dir / "s.png")->width, 20);
  EXPECT_EQ(load_weather_map(dir / "s.png")->height, 12);
  // Fed back: generate reads it (relative to the preset's folder when named in the preset).
  testutil::write_text(dir / "q.json", R"({"resolution": [40, 16, 24], "voxel_size": 50, "height": {"profile": "stratus"},
      "coverage": {"enabled": true, "kind": "image", "file": "w.png"}})");
  EXPECT_EQ(run_cli("generate -q " + (dir / "q.json") + " -o " + (dir / "q.vdb"), &out), 0) << out;
  EXPECT_TRUE(std::filesystem::exists(dir / "q.vdb"));
  // Bad input: exit 1, the field, the file and what is allowed; nothing written.
  testutil::write_text(dir / "bad.png", "GIF89a");
  for (const std::string& cmd : {"generate -q " + (dir / "p.json") + " -o " + (dir / "x.vdb"),
                                "weather-map -q " + (dir / "p.json") + " -o " + (dir / "x.png")}) {
    EXPECT_EQ(run_cli(cmd + " --set coverage.kind=image --set coverage.file=" + (dir / "bad.png"), &out), 1) << out;
    EXPECT_NE(out.find("/coverage/file: coverage.file " + (dir / "bad.png") + ": not a PNG file; a weather map is an 8- or 16-bit"),
              std::string::npos)
        << out;
    EXPECT_EQ(run_cli(cmd + " --set coverage.kind=image --set coverage.file=" + (dir / "none.png"), &out), 1) << out;
    EXPECT_NE(out.find("none.png: no such file"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "x.vdb"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
  // Never over an input: the preset's own image, or the preset.
  EXPECT_EQ(run_cli("weather-map -q " + (dir / "q.json") + " -o " + (dir / "w.png"), &out), 1) << out;
  EXPECT_EQ(run_cli("weather-map -q " + (dir / "q.json") + " -o " + (dir / "q.json"), &out), 1) << out;
  EXPECT_EQ(run_cli("generate -q " + (dir / "q.json") + " -o " + (dir / "w.png"), &out), 1) << out;
  EXPECT_NE(out.find("weather map"), std::string::npos) << out;
  EXPECT_EQ(load_weather_map(dir / "w.png")->width, 40) << "the image is still the map";
  EXPECT_EQ(run_cli("weather-map -q " + (dir / "p.json") + " --size 5000 -o " + (dir / "y.png"), &out), 1) << out;
  EXPECT_NE(out.find("--size 5000: at most 4096"), std::string::npos) << out;
  EXPECT_EQ(run_cli("weather-map --help", &out), 0);
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) EXPECT_LE(line.size(), 100u) << line;
}
