// The cloud pipeline: noise channels -> height profile -> Gaussian towers -> coverage -> threshold
// -> detail channels -> occupancy, brick by brick.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cloudgen/noise_cache.h"
#include "cloudgen/preset.h"
#include "cloudgen/volume.h"

namespace cloudgen {

inline constexpr uint32_t kBrick = 16;  ///< bricks are 16^3 voxels aligned to the volume origin
/// Detail is kept or zeroed in blocks of 16 x 8 x 8 voxels (x, y, z): two VDB leaves, whole rows.
inline constexpr uint32_t kDetailBlock = 8;

struct GenerateOptions {
  int threads = 0;         ///< 0 = all cores; output bytes are identical for any value
  bool skip_empty = true;  ///< skip noise where density provably stays 0 (never changes a value)
  bool detail = true;      ///< compute the enabled G/B/A channels (false when no output uses them)
  /// Every output bakes the erosion into density at voxel centres (export.vdb.bake_erosion): the
  /// detail channels are read only where density > 0, so they are kept only in detail blocks that
  /// hold cloud (no one-voxel reach for trilinear reads, no look at the neighbours' bound). The
  /// outputs' bytes are those of the default rule; the in-memory detail is zero in more places.
  bool detail_only_in_cloud = false;
  bool occupancy = true;   ///< build the occupancy grid
  /// Sub-box in voxels (origin, extent; extent 0 = to the end). Values equal those of the same
  /// voxels in the full run.
  std::array<uint32_t, 3> region_origin{{0, 0, 0}};
  std::array<uint32_t, 3> region_extent{{0, 0, 0}};
  std::function<void(double fraction)> progress;  ///< called from worker threads, in [0, 1]
  const std::atomic<bool>* cancel = nullptr;
  /// Raw channel noise kept between runs (noise_cache.h): a brick or detail block found there is
  /// not evaluated again, one not there is evaluated and kept. Null: nothing kept. Used only for
  /// whole-volume runs with skip_empty; the bytes are the same either way. Noise of parameters
  /// this run does not use is dropped at its end.
  NoiseCache* noise_cache = nullptr;
};

/// What a brick of a plan turned out to need, for the per-brick cost figures of --stats.
enum class BrickWork : uint8_t {
  Skipped,     ///< the bound proved density 0 here and within a voxel around: no noise at all
  DetailOnly,  ///< density 0 by the bound, but cloud may lie within a voxel: detail noise only
  Empty,       ///< density noise evaluated, no voxel above the threshold
  Cloud,       ///< density noise evaluated, some voxel holds cloud
};
inline constexpr int kBrickWorkKinds = 4;

struct GenerateStats {
  size_t bricks = 0;           ///< bricks generated (those of the region, or of a rank's share)
  size_t bricks_skipped = 0;   ///< density bricks whose noise was never evaluated
  size_t detail_bricks = 0;    ///< bricks whose detail channels were evaluated
  size_t active_voxels = 0;    ///< density > 0
  double seconds = 0;
  /// Bricks of each BrickWork kind and the thread-seconds spent on them.
  std::array<size_t, kBrickWorkKinds> work_bricks{};
  std::array<double, kBrickWorkKinds> work_seconds{};
  /// With GenerateOptions::noise_cache: channel boxes (a brick of density noise, a detail block of a
  /// detail channel) taken from the cache, and evaluated (and kept).
  size_t noise_cached = 0, noise_evaluated = 0;
};

// ---- Brick plans -------------------------------------------------------------------------------
// Generation is a plan (which bricks, their voxels, what the skipping bound lets each skip, and its
// expected cost) and the execution of any subset of it. A brick's values depend only on the preset
// and the brick, never on its neighbours or on which process computes it, so a plan can be split
// across threads, MPI ranks or farm tiles and reassembled into the one-process bytes.
//
// Detail channels hold their noise value in every 16x8x8 detail block that lies within one voxel (the
// reach of trilinear filtering, wrapping in x and z for tiling volumes) of a voxel of its own brick
// whose density is > 0, or of a voxel beyond the brick's faces that the bound allows to be > 0;
// they are 0 in all other blocks. So detail is exact wherever density, or a neighbour's density,
// is non-zero, and a brick's values still depend on nothing outside it but the noise-free bound.

struct PlannedBrick {
  std::array<uint32_t, 3> lo{}, hi{};  ///< voxel range [lo, hi) in volume coordinates, clipped to the region
  bool density = true;  ///< false: the bound proves density 0 in the whole brick
  bool detail = true;   ///< false: detail channels are 0 here (nothing within a voxel can hold cloud);
                        ///< true: some of its detail blocks may keep their noise
  double cost = 0;      ///< expected work in arbitrary units (octave-voxels of noise, plus the bound)
  size_t count() const { return size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
};

struct BrickPlan {
  std::array<uint32_t, 3> dims{};                 ///< the whole volume
  std::array<uint32_t, 3> region_lo{}, region_hi{};  ///< the part generated, [lo, hi)
  bool detail = true;                             ///< detail channels are generated at all
  std::vector<PlannedBrick> bricks;               ///< bricks meeting the region, x fastest
  double total_cost() const;
};

/// The plan of `generate(p, opt)`: opt's region and detail flag; skip_empty does not change it
/// (with skipping off, the skippable noise is evaluated and discarded, for benchmarks).
/// `first`, `count`: decide only those bricks (MPI ranks each plan a share and exchange it); the
/// others keep density = detail = true and cost 0.
BrickPlan plan_bricks(const Preset& p, const GenerateOptions& opt = {}, size_t first = 0, size_t count = SIZE_MAX);

/// One generated brick: channels over the brick's voxels (x fastest). A detail channel is empty
/// when the preset does not enable it, the plan has no detail, or the brick's detail is 0.
struct BrickResult {
  std::vector<float> density;
  std::array<std::vector<float>, 3> detail;
  bool any_density = false;  ///< some density voxel > 0
  bool any_value = false;    ///< some voxel of any channel != 0
};
/// Receives each finished brick (plan index, result); called concurrently from worker threads.
using BrickSink = std::function<void(size_t brick, BrickResult& result)>;

/// Generates the plan's bricks listed in `which` (all of them when null; none for an empty list)
/// with opt.threads workers and hands each to `sink`. Stats count only those bricks.
void execute_plan(const Preset& p, const BrickPlan& plan, const std::vector<size_t>* which,
                  const GenerateOptions& opt, const BrickSink& sink, GenerateStats* stats = nullptr);

/// The Volume that generate() fills, without channel data: dims, origin, voxel size, tiling,
/// occupancy settings and metadata (preset, seed, generator, preset_hash) of the plan's region.
Volume volume_header(const Preset& p, const BrickPlan& plan);

/// Hex digest of every preset field that changes generated values (not name, description or
/// export compression): tiles and merged outputs check it.
std::string preset_hash(const Preset& p);

/// The vertical profile (height distribution plus cloud-type gradient) at normalised height h.
double height_profile(const Preset& p, double h);
/// The continuous cloud-type gradient of cloud_type.glsl at normalised height h: type 0 stratus,
/// 0.5 cumulus, 1 cumulonimbus (bit for bit the three profiles there), linear in between.
double cloud_type_height_gradient(double h, double type);
/// The coverage map over the whole x-z plane, [z][x] (x fastest), in [0, 1]; empty when the
/// preset has no coverage (then coverage is 1 everywhere).
std::vector<float> coverage_map(const Preset& p, int threads = 0);
/// The coverage noise on a w x h grid of columns over the x-z extent ([j][i]), whether or not
/// coverage is enabled; coverage_map is this grid at the volume's x and z resolution.
std::vector<float> coverage_grid(const Preset& p, uint32_t w, uint32_t h, int threads = 0);
/// The Gaussian towers (explicit plus random), resolved to an explicit list.
std::vector<Tower> resolve_towers(const Preset& p);

Volume generate(const Preset& p, const GenerateOptions& opt = {}, GenerateStats* stats = nullptr);

/// Peak memory estimate of generate(p) in bytes, with the detail channels when `need_detail`
/// (what --max-memory and the viewer's budget compare against).
uint64_t memory_estimate(const Preset& p, bool need_detail);

/// Loads, validates and generates a preset file (what the viewer calls for .json inputs).
Volume generate_from_file(const std::string& preset_path, const std::vector<std::string>& set_overrides = {},
                          int threads = 0);

}  // namespace cloudgen
