// Tests of the NanoVDB path (issue 13, "Sparse VDBs"): cloudgen's .nvdb export against its .vdb
// export voxel for voxel, deterministic bytes, the viewer's render.volume=nanovdb (GL through
// PNanoVDB.h's GLSL mode, the CPU reference through its C mode) against the dense path, the
// dense budget's automatic switch, damaged .nvdb files, and the quantised precisions
// (export.nvdb.precision: fp16, fp8, fp4, fpn; issue 46 item 2).
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>

#include <gtest/gtest.h>

#include "cloudgen/io.h"
#include "cloudgen/nvdb.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util_viewer.h"

namespace fs = std::filesystem;
using namespace cloudviewer;
using testutil::frame_for;  // both paths framed by the same camera (the dense volume's; the boxes are equal)
using testutil::render_gl;
using testutil::with;

namespace {

fs::path dir() { return testutil::test_output_dir("nanovdb"); }

// The blob (96 x 48 x 96, detail channels), written once as .vdb and .nvdb with the same options.
const cloudgen::Volume& blob() { return testutil::synthetic("blob"); }
// Every channel as a grid (the default bakes the erosion and drops the detail grids): these tests
// are about NanoVDB carrying all of them.
cloudgen::ExportOptions all_grids() {
  cloudgen::ExportOptions o;
  o.vdb_bake_erosion = false;
  return o;
}

fs::path written(const std::string& name, cloudgen::Format f, const cloudgen::ExportOptions& o = all_grids()) {
  const fs::path p = dir() / name;
  cloudgen::write_volume(blob(), p.string(), f, o);
  return p;
}

void dump(const std::string& name, const Image& a, const Image& b) {
  write_png((dir() / (name + "_dense.png")).string(), a);
  write_png((dir() / (name + "_nanovdb.png")).string(), b);
  write_png((dir() / (name + "_diff.png")).string(), diff_image(a, b, 10));
}

void expect_same_volume(const cloudgen::Volume& a, const cloudgen::Volume& b) {
  ASSERT_EQ(a.dims, b.dims);
  EXPECT_DOUBLE_EQ(a.voxel_size, b.voxel_size);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.origin[size_t(i)], b.origin[size_t(i)], 1e-9 * (1 + std::abs(a.origin[size_t(i)])));
  EXPECT_EQ(a.tiles_xz, b.tiles_xz);
  EXPECT_EQ(a.density, b.density);  // voxel for voxel, bit for bit
  for (int c = 0; c < 3; ++c) EXPECT_EQ(a.detail[size_t(c)], b.detail[size_t(c)]) << "detail " << c;
  EXPECT_EQ(a.occupancy, b.occupancy);
}

}  // namespace

// The .nvdb export holds the .vdb export's grids: read back densely, every channel equals the
// .vdb's voxel for voxel (both up axes, normalised and physical densities), and the metadata keys
// the .vdb carries come back too (NanoVDB has no key/value metadata: cloudgen stores them in a
// blind-data block of the density grid).
TEST(NanoVdb, FileRoundTripEqualsTheVdbVoxelForVoxel) {
  for (const char* up : {"z", "y"})
    for (bool physical : {false, true}) {
      SCOPED_TRACE(std::string("up ") + up + (physical ? ", physical" : ", normalised"));
      cloudgen::ExportOptions o = all_grids();
      o.vdb_up = up[0];
      o.vdb_physical = physical;
      const cloudgen::Volume a = cloudgen::read_volume(written("rt.vdb", cloudgen::Format::Vdb, o).string());
      const cloudgen::Volume b = cloudgen::read_volume(written("rt.nvdb", cloudgen::Format::Nvdb, o).string());
      expect_same_volume(a, b);
      for (const auto& kv : a.metadata) {
        if (kv.first == "is_saved_as_half_float" || kv.first == "file_compression") continue;  // OpenVDB's own
        EXPECT_NE(std::find(b.metadata.begin(), b.metadata.end(), kv), b.metadata.end()) << kv.first;
      }
    }
  // And the sparse form's accessor lookups are the dense values at the grid index of each voxel,
  // 0 outside the box.
  const cloudgen::NanoVolume n = cloudgen::read_nvdb((dir() / "rt.nvdb").string());
  const cloudgen::Volume a = cloudgen::read_volume((dir() / "rt.vdb").string());
  ASSERT_TRUE(n.has_detail());
  EXPECT_TRUE(n.detail_shared_layout);  // one mask for the three detail grids: one tree walk
  ASSERT_EQ(n.dims, a.dims);
  size_t checked = 0;
  for (uint32_t z = 0; z < n.dims[2]; z += 7)
    for (uint32_t y = 0; y < n.dims[1]; y += 3)
      for (uint32_t x = 0; x < n.dims[0]; x += 5, ++checked) {
        const std::array<int32_t, 3> ijk{n.index_min[0] + int(x), n.index_min[1] + int(y), n.index_min[2] + int(z)};
        ASSERT_EQ(cloudgen::nano_value(n, 0, ijk), a.density[a.index(x, y, z)]);
        ASSERT_EQ(cloudgen::nano_value(n, size_t(n.detail[1]), ijk), a.detail[1][a.index(x, y, z)]);
      }
  EXPECT_GT(checked, 500u);
  // The GL renderer's page table leads to the same values (every voxel of the box, both grids).
  for (size_t g : {size_t(0), size_t(n.detail[0])}) {
    const cloudgen::NanoPages t = cloudgen::nano_pages(n, g);
    for (uint32_t z = 0; z < n.dims[2]; ++z)
      for (uint32_t y = 0; y < n.dims[1]; ++y)
        for (uint32_t x = 0; x < n.dims[0]; ++x) {
          const std::array<int32_t, 3> ijk{n.index_min[0] + int(x), n.index_min[1] + int(y), n.index_min[2] + int(z)};
          const uint32_t e = t.entries[(size_t((ijk[2] - t.origin[2]) >> 3) * t.dims[1] + size_t((ijk[1] - t.origin[1]) >> 3)) *
                                           t.dims[0] + size_t((ijk[0] - t.origin[0]) >> 3)];
          const uint32_t w = (e & cloudgen::NanoPages::kNanoConstant)
                                 ? (e & ~cloudgen::NanoPages::kNanoConstant)
                                 : e + uint32_t(((ijk[0] & 7) << 6) | ((ijk[1] & 7) << 3) | (ijk[2] & 7));
          float f;
          std::memcpy(&f, n.data() + size_t(w) * 4, 4);
          ASSERT_EQ(f, cloudgen::nano_value(n, g, ijk)) << "grid " << g << " at " << x << "," << y << "," << z;
        }
  }
  EXPECT_EQ(cloudgen::nano_value(n, 0, {n.index_min[0] - 40, n.index_min[1], n.index_min[2]}), 0.0f);
}

// Same preset, same bytes: one thread or many, and twice in one process (NanoVDB leaves padding
// uninitialised; cloudgen converts into zeroed memory).
TEST(NanoVdb, BytesAreTheSameAtAnyThreadCount) {
  std::string one, many, again;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = testutil::read_text(written("t1.nvdb", cloudgen::Format::Nvdb));
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 8);
    many = testutil::read_text(written("t8.nvdb", cloudgen::Format::Nvdb));
  }
  again = testutil::read_text(written("t8b.nvdb", cloudgen::Format::Nvdb));
  ASSERT_GT(one.size(), 1000u);
  EXPECT_TRUE(one == many);
  EXPECT_TRUE(many == again);
}

// The occupancy grid of the nanovdb path comes from the density grid's leaves and tiles, and holds
// exactly the cells the dense builder marks (voxel granularity), so skipping skips the same cells.
TEST(NanoVdb, OccupancyFromLeavesEqualsTheDenseBuilder) {
  const fs::path p = written("occ.nvdb", cloudgen::Format::Nvdb);
  for (int cell : {4, 8})
    for (int pad : {1, 2}) {
      RenderSettings dense = with({"render.volume=dense"}), nano = with({"render.volume=nanovdb"});
      dense.occupancy_cell = nano.occupancy_cell = cell;
      dense.occupancy_padding = nano.occupancy_padding = pad;
      const PreparedVolume a = open_input(p.string(), dense), b = open_input(p.string(), nano);
      ASSERT_FALSE(a.nano);
      ASSERT_TRUE(b.nano);
      EXPECT_TRUE(b.rgba.empty());  // no dense copy on the nanovdb path
      EXPECT_EQ(a.occ_dims, b.occ_dims);
      EXPECT_EQ(a.occ, b.occ) << "cell " << cell << ", padding " << pad;
    }
}

// Same view through dense and nanovdb. The nanovdb lookups filter by hand with medium.glsl's
// trilinear formula and the grids hold the dense texture's float values, so:
//  - CPU reference: the same double arithmetic on the same values: max |diff| = 0;
//  - GL against the dense path with render.exact_filter=true (the same hand filter over
//    texelFetch): the same float arithmetic, max |diff| <= 1e-6 (measured 0 on llvmpipe);
//  - GL against the dense default (the texture unit's filter): llvmpipe filters RGBA32F in float
//    (measured 0 here too); quantising hardware may differ by ~1/256 of a voxel step, so > 45 dB.
TEST(NanoVdb, SameViewGivesTheSameImageAsTheDensePath) {
  const fs::path p = written("view.nvdb", cloudgen::Format::Nvdb);
  const PreparedVolume dense = open_input(p.string(), with({"render.volume=dense"}));
  const PreparedVolume nano = open_input(p.string(), with({"render.volume=nanovdb"}));
  ASSERT_TRUE(nano.nano);
  // The height range of the height fraction (ambient gradient, motion) is the dense path's too.
  EXPECT_EQ(nano.height_min, dense.height_min);
  EXPECT_EQ(nano.height_size, dense.height_size);
  EXPECT_EQ(nano.baked_motion, dense.baked_motion);
  RenderSettings s = with({"render.steps=96"});
  const FrameSetup f = frame_for(dense, s, 96, 54);
  const FrameImages cd = render_cpu(dense, f), cn = render_cpu(nano, f);
  EXPECT_EQ(max_abs_diff(cd.linear, cn.linear), 0.0);
  const FrameImages gd = render_gl(dense, f), gn = render_gl(nano, f);
  const double hw = psnr(gd.display, gn.display);
  std::cout << "GL dense (texture unit) vs nanovdb: max |diff| " << max_abs_diff(gd.linear, gn.linear) << ", PSNR " << hw
            << " dB\n";
  EXPECT_GT(hw, 45.0);
  const ImageStats st = image_stats(gn.display);
  EXPECT_EQ(st.nonfinite, 0);
  EXPECT_GT(st.stddev, 0.05);  // the cloud is there, not a flat sky
  RenderSettings ex = with({"render.steps=96", "render.exact_filter=true"});
  const FrameSetup fe = frame_for(dense, ex, 96, 54);
  const FrameImages ed = render_gl(dense, fe), en = render_gl(nano, fe);
  const double d = max_abs_diff(ed.linear, en.linear);
  std::cout << "GL dense (exact filter) vs nanovdb: max |diff| " << d << "\n";
  EXPECT_LE(d, 1e-6);
  // GL nanovdb against the CPU nanovdb reference, as the dense path's own test (> 50 dB).
  const FrameImages cpu_e = render_cpu(nano, fe);
  EXPECT_GT(psnr(en.display, cpu_e.display), 50.0);
  // The default GPU lookup is the brick atlas (en above); the page table and PNanoVDB's accessor
  // walk read the same values with the same hand filter: the same image.
  for (const char* lookup : {"render.nanovdb_lookup=table", "render.nanovdb_lookup=accessor"}) {
    RenderSettings other = ex;
    apply_setting(other, lookup);
    EXPECT_EQ(max_abs_diff(render_gl(nano, frame_for(dense, other, 96, 54)).linear, en.linear), 0.0) << lookup;
  }
  // Detail grids of separate layouts (files from elsewhere) take one tree walk per grid: same image.
  auto copy = std::make_shared<cloudgen::NanoVolume>(*nano.nano);
  copy->detail_shared_layout = false;
  const PreparedVolume separate = prepare_nano(copy, nano.occ_cell, nano.occ_padding);
  EXPECT_EQ(max_abs_diff(render_cpu(separate, f).linear, cd.linear), 0.0);
  EXPECT_LE(max_abs_diff(render_gl(separate, fe).linear, ed.linear), 1e-6);
  if (HasFailure()) dump("same_view", gd.display, gn.display);
}

// The brick atlas (the default lookup) needs neither the grids nor the page table on the GPU, so
// they stay on the CPU until a frame reads them (cumulus-field 2048's grids are 637 MiB): a
// renderer that only drew through the atlas has not uploaded them, the first table frame does, and
// that frame is the fresh table renderer's frame (within float rounding). The load line's estimate follows.
TEST(NanoVdb, GridsGoToTheGpuOnlyWhenALookupReadsThem) {
  const fs::path p = written("lazy.nvdb", cloudgen::Format::Nvdb);
  const PreparedVolume nano = open_input(p.string(), with({"render.volume=nanovdb"}));
  ASSERT_TRUE(nano.nano);
  const RenderSettings atlas = with({"render.steps=64"}), table = with({"render.steps=64", "render.nanovdb_lookup=table"});
  testutil::gl_context();
  GlRenderer r{ShaderSource()};
  r.set_volume(nano);
  EXPECT_FALSE(r.stats().nano_grids_on_gpu);
  r.render(frame_for(nano, atlas, 64, 36));
  EXPECT_FALSE(r.stats().nano_grids_on_gpu) << "the atlas frame uploaded the grids";
  const FrameImages via_atlas = r.read_back();
  r.render(frame_for(nano, table, 64, 36));
  EXPECT_TRUE(r.stats().nano_grids_on_gpu);
  const FrameImages via_table = r.read_back();
  // (float rounding apart: this renderer's light volume and air tables come from its first frame;
  // a frame through the placeholders would read no cloud at all)
  EXPECT_LE(max_abs_diff(via_table.linear, render_gl(nano, frame_for(nano, table, 64, 36)).linear), 1e-6);
  EXPECT_GT(psnr(via_atlas.display, via_table.display), 45.0);  // the two lookups, as in SameView...
  // A new volume puts placeholders back until a lookup reads it again.
  r.set_volume(nano);
  EXPECT_FALSE(r.stats().nano_grids_on_gpu);
  const uint64_t skipping = nano.occ.size() * 2;
  EXPECT_EQ(volume_gpu_bytes(nano, NanoLookup::Atlas), skipping);
  EXPECT_GE(volume_gpu_bytes(nano, NanoLookup::Table), nano_grid_bytes(nano) + skipping);
  EXPECT_GT(nano_grid_bytes(nano), 0u);
  const PreparedVolume dense = open_input(p.string(), with({"render.volume=dense"}));
  EXPECT_EQ(nano_grid_bytes(dense), 0u);
  EXPECT_EQ(volume_gpu_bytes(dense, NanoLookup::Atlas), uint64_t(dense.rgba.size()) * sizeof(float) + dense.occ.size() * 2);
}

// A tiling volume whose sides are not whole leaves (100 x 40 x 92 voxels, the noise repeated):
// a brick at the wrap reads leaf cells from both ends of the tile.
cloudgen::Volume odd_tiling_volume() {
  const cloudgen::Volume& src = testutil::synthetic("noise");
  cloudgen::Volume v = src;
  v.dims = {100, 40, 92};
  v.density.assign(v.voxel_count(), 0.f);
  for (auto& d : v.detail) d.assign(v.voxel_count(), 0.f);
  for (uint32_t z = 0; z < v.dims[2]; ++z)
    for (uint32_t y = 0; y < v.dims[1]; ++y)
      for (uint32_t x = 0; x < v.dims[0]; ++x) {
        const size_t from = src.index(x % src.dims[0], y + 4, z % src.dims[2]), to = v.index(x, y, z);
        v.density[to] = src.density[from];
        for (int c = 0; c < 3; ++c) v.detail[size_t(c)][to] = src.detail[size_t(c)][from];
      }
  v.occupancy.clear();
  return v;
}

// The brick atlas (render.nanovdb_lookup=atlas) against an independent reading of the grids:
// every texel of every brick is the dense texture's texel at its clamped or wrapped index, as
// NanoVDB's own accessor reads it (cloudgen::nano_value); a cell without a brick reads no density
// anywhere in its 9^3; a tiling volume wraps. A budget below the atlas's size gives none.
TEST(NanoVdb, BrickAtlasHoldsTheDenseTexels) {
  for (const char* kind : {"blob", "noise", "odd"}) {
    const cloudgen::Volume v = std::string(kind) == "odd" ? odd_tiling_volume() : testutil::synthetic(kind);
    auto n = std::make_shared<cloudgen::NanoVolume>(cloudgen::nano_from_volume(v, all_grids()));
    const PreparedVolume pv = prepare_nano(n, 8, 1);
    ASSERT_EQ(pv.tiles, std::string(kind) != "blob");
    std::cout << kind << ": box " << pv.dims[0] << "x" << pv.dims[1] << "x" << pv.dims[2] << " from index " << n->index_min[0]
              << "," << n->index_min[1] << "," << n->index_min[2] << "\n";
    const NanoAtlas a = build_nano_atlas(pv, 2048, uint64_t(1) << 30);
    ASSERT_GT(a.cells[0], 0) << kind;
    ASSERT_EQ(a.channels, 4);
    const int B = NanoAtlas::kBrick;
    const size_t W = size_t(a.layout[0]) * B, H = size_t(a.layout[1]) * B;
    size_t with_brick = 0, checked = 0;
    uint32_t state = 3;
    auto next = [&](int m) { return int(((state = state * 1664525u + 1013904223u) >> 8) % uint32_t(m)); };
    for (int cz = 0; cz < a.cells[2]; ++cz)
      for (int cy = 0; cy < a.cells[1]; ++cy)
        for (int cx = 0; cx < a.cells[0]; ++cx) {
          const uint16_t* e = &a.index[((size_t(cz) * a.cells[1] + cy) * a.cells[0] + cx) * 4];
          with_brick += e[3];
          // Some texels of each cell (all 729 of every 7th), at the index the dense sampler reads.
          const int samples = (cx + cy + cz) % 7 == 0 ? B * B * B : 24;
          for (int s = 0; s < samples; ++s) {
            const int x = samples == B * B * B ? s % B : next(B), y = samples == B * B * B ? (s / B) % B : next(B),
                      z = samples == B * B * B ? s / (B * B) : next(B);
            const int t[3] = {8 * cx - 1 + x, 8 * cy - 1 + y, 8 * cz - 1 + z};
            std::array<int32_t, 3> ijk;
            for (int k = 0; k < 3; ++k) {
              const int d = pv.dims[size_t(k)];
              const int i = pv.tiles && k != 1 ? ((t[k] % d) + d) % d : std::clamp(t[k], 0, d - 1);
              ijk[size_t(k)] = i + n->index_min[size_t(k)];
            }
            const float want = std::max(cloudgen::nano_value(*n, 0, ijk), 0.0f);
            if (e[3] == 0) {
              ASSERT_EQ(want, 0.0f) << kind << " cell " << cx << "," << cy << "," << cz << " has density but no brick";
              continue;
            }
            const float* got = &a.texels[(((size_t(e[2]) + z) * H + e[1] + y) * W + e[0] + x) * 4];
            ASSERT_EQ(got[0], want) << kind << " cell " << cx << "," << cy << "," << cz << " texel " << x << "," << y << "," << z;
            for (int c = 0; c < 3; ++c)
              ASSERT_EQ(got[1 + c], cloudgen::nano_value(*n, size_t(n->detail[size_t(c)]), ijk)) << kind << " detail " << c;
            ++checked;
          }
        }
    EXPECT_EQ(with_brick, a.bricks);
    EXPECT_GT(a.bricks, 0u);
    EXPECT_GT(checked, 10000u) << kind;
    if (std::string(kind) == "blob") {
      EXPECT_LT(a.bricks, size_t(a.cells[0]) * a.cells[1] * a.cells[2]) << "empty cells keep no brick";
    }
    EXPECT_EQ(build_nano_atlas(pv, 2048, a.bytes() / 2).cells[0], 0) << "over the budget: no atlas";
  }
}

// A tiling volume through the atlas on the GPU (sides not whole leaves): the wrap at the tile's
// sides reads the dense texture's texels (exact filter: the same float arithmetic, <= 1e-6) and filters as its sampler.
TEST(NanoVdb, AtlasOfATilingVolumeGivesTheDenseImage) {
  const cloudgen::Volume v = odd_tiling_volume();
  auto n = std::make_shared<cloudgen::NanoVolume>(cloudgen::nano_from_volume(v, all_grids()));
  const PreparedVolume nano = prepare_nano(n, 8, 1);
  const PreparedVolume dense = prepare_volume(v, 8, 1);
  ASSERT_TRUE(nano.tiles);
  RenderSettings ex = with({"render.steps=96", "render.exact_filter=true"});
  const FrameSetup fe = frame_for(dense, ex, 96, 54);
  const double d = max_abs_diff(render_gl(dense, fe).linear, render_gl(nano, fe).linear);
  std::cout << "tiling volume, GL dense vs atlas (exact filter): max |diff| " << d << "\n";
  EXPECT_LE(d, 1e-6);
  RenderSettings s = with({"render.steps=96"});
  const FrameSetup f = frame_for(dense, s, 96, 54);
  const FrameImages gd = render_gl(dense, f), gn = render_gl(nano, f);
  std::cout << "tiling volume, GL dense vs atlas (texture unit): PSNR " << psnr(gd.display, gn.display) << " dB\n";
  EXPECT_GT(psnr(gd.display, gn.display), 45.0);
  EXPECT_GT(image_stats(gn.display).stddev, 0.05);
}

// render.skipping=tree, the hierarchical DDA through the NanoVDB tree (issue 13): jumps through
// the density grid's empty nodes keep exactly the samples of the plain march, max |diff| = 0 on GL
// and on the CPU reference, and take fewer loop trips. Paths: the primary march's exit along the
// ray in box mode (still, and moving with the bend the motion allows); the radius in any direction
// (layer mode; the light and shadow marches with render.occupancy_light). Volumes: the blob with
// its detail grids; the tiling volume whose sides are not whole leaves (nodes cut at the wrap),
// without detail grids (the atlas programs then read no nanovdb uniform but the tree's) and with
// its first rows empty, so the grid's index box does not start at 0 (nodes are aligned in index
// space, not in the volume's). A radius 32x too long changes the image: the check can fail. A
// dense volume refuses the setting with a message naming the way out.
TEST(NanoVdb, TreeSkippingKeepsEverySampleOfThePlainMarch) {
  struct Case {
    const char* name;
    PreparedVolume vol;
    std::vector<const char*> sets;
    double time = 0;  // s: the default motion moves the clouds once time passes
  };
  std::vector<Case> cases;
  {
    const fs::path p = written("tree.nvdb", cloudgen::Format::Nvdb);
    const PreparedVolume blob_nano = open_input(p.string(), with({"render.volume=nanovdb"}));
    cases.push_back({"blob, still", blob_nano, {"render.steps=128", "motion.wind_speed=0", "motion.flow_up=0", "motion.flow_forward=0"}});
    // Moving: the wind with its height shear (the flow map's steep slope would leave radii under a step).
    cases.push_back({"blob, moving", blob_nano, {"render.steps=128", "motion.flow_up=0", "motion.flow_forward=0"}, 40.0});
    cases.push_back({"blob, light and shadow by the tree", blob_nano,
                     {"render.steps=128", "render.occupancy_light=true", "render.light_volume=false", "render.shadow_map=false"}});
  }
  cloudgen::Volume t = odd_tiling_volume();
  for (uint32_t z = 0; z < t.dims[2]; ++z)
    for (uint32_t y = 0; y < 3; ++y)
      for (uint32_t x = 0; x < t.dims[0]; ++x) t.density[t.index(x, y, z)] = 0.f;
  auto tn = std::make_shared<cloudgen::NanoVolume>(cloudgen::nano_from_volume(t, cloudgen::ExportOptions{}));
  ASSERT_NE(tn->index_min[1], 0) << "a grid whose index box starts at 0 would not test the offset";
  const PreparedVolume tiling = prepare_nano(tn, 8, 1);
  ASSERT_TRUE(tiling.tiles);
  ASSERT_FALSE(tiling.has_detail);
  cases.push_back({"tiling, still", tiling, {"render.steps=96", "motion.wind_speed=0", "motion.flow_up=0", "motion.flow_forward=0"}});
  cases.push_back({"tiling, layer mode", tiling, {"render.steps=96", "render.mode=layer", "motion.wind_speed=0", "motion.flow_up=0", "motion.flow_forward=0"}});
  for (const Case& c : cases)
    for (bool on_gl : {true, false}) {
      if (!on_gl && std::string(c.name) == "tiling, layer mode") continue;  // long rays: GL only
      const std::string what = std::string(c.name) + (on_gl ? " GL" : " CPU");
      RenderSettings none, tree;
      for (const char* a : c.sets) apply_setting(none, a), apply_setting(tree, a);
      apply_setting(none, "render.skipping=none");
      apply_setting(tree, "render.skipping=tree");
      none.time = tree.time = c.time;
      // 96x54, or 32x18 under the sanitizers (test_util.h): the CPU march through the tree is the
      // suite's costliest there.
      const int w = testutil::sized(96, 32), h = testutil::sized(54, 18);
      const FrameSetup fn = frame_for(c.vol, none, w, h), ft = frame_for(c.vol, tree, w, h);
      ASSERT_EQ(ft.params.skip_tree, 1.0) << what;
      auto draw = [&](const FrameSetup& f) { return testutil::render_on(on_gl, c.vol, f); };
      const FrameImages a = draw(fn), b = draw(ft);
      EXPECT_GT(image_stats(a.display).stddev, 0.01) << what << ": a picture to compare";
      EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << what;
      auto trips = [&](FrameSetup f) {
        f.params.output_mode = CV_OUTPUT_ITERATIONS;
        return testutil::loop_trips_sum(draw(f)) / (double(w) * h);
      };
      const double tn_trips = trips(fn), tt_trips = trips(ft);
      std::cout << what << ": loop trips per pixel none " << tn_trips << ", tree " << tt_trips << "\n";
      // Layer mode reads the radius in any direction (the ray bends through the texture), which an
      // 8-voxel tile keeps near one step: fewer trips, not many fewer.
      EXPECT_LT(tt_trips, (ft.params.layer_on > 0.5 ? 0.99 : 0.9) * tn_trips) << what;
      if (std::string(c.name) == "tiling, layer mode") {
        FrameSetup bad = ft;
        bad.params.df_cell_m *= 32.0;  // the radius is in voxels of df_cell_m / occ_cell_voxels metres
        EXPECT_GT(max_abs_diff(a.linear, draw(bad).linear), 1e-3) << what << ": the check can fail";
      }
      if (HasFailure()) dump("tree_" + std::to_string(&c - cases.data()), a.display, b.display);
    }
  const PreparedVolume dense = open_input(written("tree_dense.vdb", cloudgen::Format::Vdb).string(), with({"render.volume=dense"}));
  try {
    frame_for(dense, with({"render.skipping=tree"}));
    ADD_FAILURE() << "a dense volume took render.skipping=tree";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("render.volume=nanovdb"), std::string::npos) << e.what();
  }
}

// A volume beyond the dense path's budget (here a deliberately small render.dense_budget) opens
// and renders through NanoVDB under volume=auto, from .nvdb, from .vdb (converted sparse, no
// dense copy) and from a raw texture; volume=dense refuses it naming the setting.
// volume=auto: dense within the budget and below a 2 GiB texture, nanovdb beyond either (a
// texture of cumulus-field 1024, 2.4 GB, fails on llvmpipe with any budget); dense and nanovdb obey.
TEST(NanoVdb, AutoStorageKeepsTheDenseTextureUnderTwoGiB) {
  const RenderSettings roomy = with({"render.dense_budget=100000"});  // MiB: the budget is not the limit
  const uint64_t limit_voxels = kDenseTextureLimit / 16;
  EXPECT_FALSE(use_nanovdb(roomy, limit_voxels - 1));
  EXPECT_TRUE(use_nanovdb(roomy, limit_voxels));
  EXPECT_TRUE(use_nanovdb(roomy, uint64_t(1024) * 146 * 1024));
  EXPECT_FALSE(use_nanovdb(with({"render.dense_budget=100000", "render.volume=dense"}), limit_voxels * 2));
  EXPECT_TRUE(use_nanovdb(with({"render.volume=nanovdb"}), 8));
  const RenderSettings tight = with({"render.dense_budget=1"});  // 1 MiB: 65,000 voxels
  EXPECT_FALSE(use_nanovdb(tight, 60000));
  EXPECT_TRUE(use_nanovdb(tight, 70000));
}

TEST(NanoVdb, VolumeBeyondTheDenseBudgetRendersThroughNanoVdb) {
  const fs::path nvdb = written("big.nvdb", cloudgen::Format::Nvdb);
  const fs::path vdb = written("big.vdb", cloudgen::Format::Vdb);
  const fs::path raw = written("big.raw", cloudgen::Format::Raw);
  // The blob's dense copy: its active box, 66 x 21 x 62 voxels x 16.125 B = 1.3 MiB; the budget
  // is 0.5 MiB.
  const RenderSettings small = with({"render.dense_budget=0.5"});
  const PreparedVolume ref = open_input(nvdb.string(), with({"render.volume=dense"}));
  const FrameSetup f = frame_for(ref, RenderSettings{}, 96, 54);
  const FrameImages want = render_gl(ref, f);
  for (const fs::path& p : {nvdb, vdb, raw}) {
    SCOPED_TRACE(p.string());
    const PreparedVolume v = open_input(p.string(), small);
    ASSERT_TRUE(v.nano);
    EXPECT_TRUE(v.rgba.empty());  // no dense copy
    const FrameImages got = render_gl(v, f);
    EXPECT_GT(psnr(want.display, got.display), 45.0);
  }
  // Under a generous budget auto stays dense.
  EXPECT_FALSE(open_input(nvdb.string(), with({"render.dense_budget=64"})).nano);
  try {
    open_input(nvdb.string(), with({"render.dense_budget=0.5", "render.volume=dense"}));
    ADD_FAILURE() << "volume=dense beyond the budget was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("render.dense_budget"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nanovdb"), std::string::npos) << e.what();
  }
}

// Damaged .nvdb files: every truncation, flipped bytes in the header, descriptors and grid data,
// a wrong magic, an empty file, a compressed file and one without a density grid are refused with
// InputError naming the file, never a crash or another exception.
TEST(NanoVdb, DamagedFilesGiveClearErrors) {
  const std::string good = testutil::read_text(written("good.nvdb", cloudgen::Format::Nvdb));
  const fs::path bad = dir() / "bad.nvdb";
  auto refused = [&](const std::string& b, const std::string& what, const char* needle = nullptr) {
    testutil::write_text(bad, b);
    try {
      cloudgen::read_nvdb(bad.string());
      ADD_FAILURE() << what << ": accepted";
    } catch (const cloudgen::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << what << ": " << e.what();
      if (needle) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << what << ": " << e.what();
      }
    }
  };
  refused("", "empty", "runs past the end");
  for (size_t n : {size_t(8), size_t(16), size_t(100), size_t(200), size_t(1000), good.size() / 2, good.size() - 32,
                   good.size() - 1})
    refused(good.substr(0, n), "truncated to " + std::to_string(n));
  std::string b = good;
  b[0] ^= 0x55;
  refused(b, "magic", "magic");
  b = good;
  b[14] = 1;  // codec: ZIP
  refused(b, "compressed", "compressed");
  b = good;
  b[14] = 0;  // codec 256: beyond NanoVDB's own name table (its toStr read past it; found by fuzz_nvdb)
  b[15] = 1;
  refused(b, "unknown codec", "unknown codec 256");
  // Flipped bytes anywhere in the grids: the checksum (or a structure check) catches them.
  for (size_t at = 300; at < good.size(); at += good.size() / 37) {
    b = good;
    b[at] = char(b[at] ^ 0x5a);
    testutil::write_text(bad, b);
    try {
      cloudgen::read_nvdb(bad.string());
      // A flip in padding the checksum does not cover is harmless: the file must still read.
    } catch (const cloudgen::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
    }
  }
  // No density grid: rename it in the file's grid descriptor.
  b = good;
  b.replace(b.find("density"), 7, "densitz");
  refused(b, "no density grid", "no float grid named \"density\"");
  // The viewer passes the reader's message on.
  testutil::write_text(bad, good.substr(0, good.size() / 3));
  EXPECT_THROW(open_input(bad.string(), RenderSettings{}), cloudgen::InputError);
}

// ---------------------------------------------------------------------------------------------
// Quantised grids (export.nvdb.precision). NanoVDB stores each 8^3 leaf as min + code * q, with
// q = (max - min) / (2^bits - 1) over the leaf's values, rounding to the nearest code: a voxel is
// off by at most q / 2, so by at most (channel range) / (2 (2^bits - 1)) (FpN: the tolerance).

namespace {

cloudgen::ExportOptions quantised(cloudgen::NvdbPrecision p, double tolerance = 0.01) {
  cloudgen::ExportOptions o = all_grids();
  o.nvdb_precision = p;
  o.nvdb_tolerance = tolerance;
  return o;
}

std::string meta(const cloudgen::Volume& v, const std::string& key) {
  for (const auto& [k, val] : v.metadata)
    if (k == key) return val;
  return "";
}

}  // namespace

// Every precision reads back (decoded to float) on the float file's box and transform, every
// channel within its bound, and quantised for real (the largest error is a good part of the bound).
TEST(NanoVdb, QuantisedGridsReadBackWithinTheirBounds) {
  using P = cloudgen::NvdbPrecision;
  struct Case {
    P p;
    int bits;  // 0: fpn
    double tolerance;
  };
  for (const char* up : {"z", "y"}) {
    cloudgen::ExportOptions fo = all_grids();
    fo.vdb_up = up[0];
    const cloudgen::Volume exact = cloudgen::read_volume(written(std::string("exact_") + up + ".nvdb", cloudgen::Format::Nvdb, fo).string());
    ASSERT_FALSE(exact.detail[0].empty());
    for (const Case c : {Case{P::Fp16, 16, 0}, Case{P::Fp8, 8, 0}, Case{P::Fp4, 4, 0}, Case{P::FpN, 0, 0.01},
                         Case{P::FpN, 0, 0.002}}) {
      const std::string name = cloudgen::nvdb_precision_name(c.p);
      SCOPED_TRACE(name + ", tolerance " + std::to_string(c.tolerance) + ", up " + up);
      cloudgen::ExportOptions o = quantised(c.p, c.tolerance);
      o.vdb_up = up[0];
      const fs::path path = written("q_" + name + "_" + up + ".nvdb", cloudgen::Format::Nvdb, o);
      const cloudgen::NanoVolume n = cloudgen::read_nvdb(path.string());
      for (const auto& g : n.grids) EXPECT_EQ(g.precision, name) << g.name;
      const cloudgen::Volume v = cloudgen::read_volume(path.string());
      ASSERT_EQ(v.dims, exact.dims);
      EXPECT_DOUBLE_EQ(v.voxel_size, exact.voxel_size);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(v.origin[size_t(a)], exact.origin[size_t(a)], 1e-9);
      EXPECT_EQ(meta(v, "nvdb_precision"), name);
      ASSERT_FALSE(v.detail[0].empty());
      for (int ch = 0; ch < 4; ++ch) {
        const std::vector<float>& a = ch == 0 ? exact.density : exact.detail[size_t(ch - 1)];
        const std::vector<float>& b = ch == 0 ? v.density : v.detail[size_t(ch - 1)];
        ASSERT_EQ(a.size(), b.size());
        const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
        const double range = double(*hi) - std::min(0.0, double(*lo));
        const double bound = c.bits ? range / (2.0 * ((1 << c.bits) - 1)) * 1.0001 + 1e-6 : c.tolerance + 1e-6;
        double worst = 0;
        for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(double(a[i]) - b[i]));
        std::cout << name << " up " << up << " channel " << ch << ": max |error| " << worst << " (bound " << bound
                  << ", range " << range << ")\n";
        EXPECT_LE(worst, bound) << "channel " << ch;
        if (c.bits && c.bits <= 8) {
          EXPECT_GT(worst, 0.1 * bound) << "channel " << ch << ": not quantised?";
        }
      }
    }
  }
}

// Fewer bits, fewer bytes: float > fp16 > fp8 > fp4, and fpn shrinks as its tolerance grows.
TEST(NanoVdb, QuantisedFilesAreSmallerByPrecision) {
  using P = cloudgen::NvdbPrecision;
  auto size_of = [](const std::string& name, const cloudgen::ExportOptions& o) {
    return fs::file_size(written(name, cloudgen::Format::Nvdb, o));
  };
  const auto f = size_of("s_float.nvdb", all_grids()), h = size_of("s_fp16.nvdb", quantised(P::Fp16)),
             e = size_of("s_fp8.nvdb", quantised(P::Fp8)), q = size_of("s_fp4.nvdb", quantised(P::Fp4)),
             n_fine = size_of("s_fpn_fine.nvdb", quantised(P::FpN, 0.0005)),
             n_coarse = size_of("s_fpn_coarse.nvdb", quantised(P::FpN, 0.05));
  std::cout << "bytes: float " << f << ", fp16 " << h << ", fp8 " << e << ", fp4 " << q << ", fpn 0.0005 " << n_fine
            << ", fpn 0.05 " << n_coarse << "\n";
  EXPECT_GT(f, h);
  EXPECT_GT(h, e);
  EXPECT_GT(e, q);
  EXPECT_GT(f, n_fine);
  EXPECT_GT(n_fine, n_coarse);
}

// An fpn tolerance of 0 or below is refused before anything is written: from a preset key (exit
// 1, the key, the value and the range in the message) and from ExportOptions set by code.
TEST(NanoVdb, FpnToleranceOutOfRangeIsRefused) {
  for (const char* t : {"0", "-0.01"}) {
    const fs::path out = dir() / (std::string("tol_") + t + ".nvdb");
    std::string text;
    const int code = testutil::run_cli("generate tiny -q -o " + out.string() +
                                           " --set export.nvdb.precision=fpn --set export.nvdb.tolerance=" + t,
                                       &text);
    EXPECT_EQ(code, 1) << text;
    EXPECT_NE(text.find("/export/nvdb/tolerance"), std::string::npos) << text;
    EXPECT_NE(text.find("allowed: number in [1e-06, 1000]"), std::string::npos) << text;
    EXPECT_FALSE(fs::exists(out)) << t;
    cloudgen::ExportOptions o = quantised(cloudgen::NvdbPrecision::FpN, std::stod(t));
    EXPECT_THROW(cloudgen::write_volume(blob(), out.string(), cloudgen::Format::Nvdb, o), cloudgen::InputError);
    EXPECT_FALSE(fs::exists(out)) << t;
  }
  std::string text;
  EXPECT_EQ(testutil::run_cli("generate tiny -q -o " + (dir() / "p.nvdb").string() + " --set export.nvdb.precision=fp12",
                              &text),
            1);
  EXPECT_NE(text.find("float | fp16 | fp8 | fp4 | fpn"), std::string::npos) << text;
}

// The viewer opens every precision (dense and nanovdb paths: the reader decodes), and the image
// is the float file's within what the precision allows (CPU reference, linear PSNR).
TEST(NanoVdb, QuantisedFilesRenderCloseToTheFloatFile) {
  using P = cloudgen::NvdbPrecision;
  const fs::path fp = written("r_float.nvdb", cloudgen::Format::Nvdb);
  const PreparedVolume ref = open_input(fp.string(), with({"render.volume=nanovdb"}));
  RenderSettings s = with({"render.steps=96"});
  const FrameSetup f = frame_for(ref, s, 96, 54);
  const FrameImages base = render_cpu(ref, f);
  double last = 1e9;
  for (const P p : {P::Fp16, P::Fp8, P::Fp4}) {
    const std::string name = cloudgen::nvdb_precision_name(p);
    const fs::path qp = written("r_" + name + ".nvdb", cloudgen::Format::Nvdb, quantised(p));
    const PreparedVolume nano = open_input(qp.string(), with({"render.volume=nanovdb"}));
    const PreparedVolume dense = open_input(qp.string(), with({"render.volume=dense"}));
    ASSERT_TRUE(nano.nano);
    ASSERT_FALSE(dense.nano);
    const FrameImages a = render_cpu(nano, f), b = render_cpu(dense, f);
    EXPECT_EQ(max_abs_diff(a.linear, b.linear), 0.0) << name;  // one decoded grid, two paths
    const double db = psnr(base.linear, a.linear, 1.0);
    std::cout << name << ": PSNR against float " << db << " dB\n";
    EXPECT_GT(db, 30.0) << name;
    EXPECT_LT(db, last) << name << ": fewer bits, no closer";
    last = db;
  }
}

// Damaged quantised files: truncations, flips with and without the checksum, and an FpN leaf
// claiming a bit width beyond 16 give InputError naming the file, never a crash.
TEST(NanoVdb, DamagedQuantisedFilesGiveClearErrors) {
  const fs::path bad = dir() / "bad_q.nvdb";
  // The file layout (nanovdb::io, as fuzz_nvdb reads it): a 16-byte header (grid count at byte 12),
  // per grid a 176-byte descriptor (grid size at 0, name size at 136) and its name, then the
  // grids. In a grid: the checksum at bytes 8..15 (all ones: none), the tree after the 672-byte
  // grid header, starting with the leaves' offset from the tree; a leaf's flags at its byte 15.
  auto first_grid = [](const std::string& f) {
    uint32_t name_size = 0;
    std::memcpy(&name_size, f.data() + 16 + 136, 4);
    uint16_t count = 0;
    std::memcpy(&count, f.data() + 12, 2);
    EXPECT_EQ(count, 1);  // density only: the default bakes the erosion
    return size_t(16 + 176 + name_size);
  };
  auto try_read = [&](const std::string& b, const char* needle = nullptr) {
    testutil::write_text(bad, b);
    try {
      (void)cloudgen::read_volume(bad.string());
      if (needle) ADD_FAILURE() << "accepted; expected " << needle;
    } catch (const cloudgen::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
      if (needle) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      }
    }
  };
  for (const auto p : {cloudgen::NvdbPrecision::Fp4, cloudgen::NvdbPrecision::FpN}) {
    const std::string good =
        testutil::read_text(written(std::string("good_") + cloudgen::nvdb_precision_name(p) + ".nvdb",
                                    cloudgen::Format::Nvdb, quantised(p, 0.01) /* all_grids: 4 grids */));
    cloudgen::ExportOptions dens = quantised(p, 0.01);
    dens.vdb_bake_erosion = true;
    const std::string one = testutil::read_text(written("good_density.nvdb", cloudgen::Format::Nvdb, dens));
    for (size_t n : {size_t(100), good.size() / 2, good.size() - 32}) try_read(good.substr(0, n), "");
    const size_t g = first_grid(one);
    std::string open = one;
    std::memset(&open[g + 8], 0xff, 8);
    try_read(open);  // no checksum: reads
    EXPECT_NO_THROW(cloudgen::read_volume(bad.string()));
    for (const std::string* base : std::vector<const std::string*>{&good, &open})
      for (size_t at = 300; at < base->size(); at += base->size() / 53) {
        std::string b = *base;
        b[at] = char(b[at] ^ 0xe0);  // the FpN bit-width bits among others
        try_read(b);
      }
    if (p == cloudgen::NvdbPrecision::FpN) {
      uint64_t leaves = 0;
      std::memcpy(&leaves, open.data() + g + 672, 8);
      std::string b = open;
      b[g + 672 + leaves + 15] = char(0xe0);  // log2 of the bit width: 7, 128 bits a value
      try_read(b, "bits a value");
    }
  }
}
