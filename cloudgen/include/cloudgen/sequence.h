// Baking cloud motion into a VDB sequence (`cloudgen generate PRESET --frames A:B --fps F -o
// out/cloud_####.vdb`): each frame is the static volume displaced by motion.glsl's D(h, t) at
// t = frame / fps, the formula the viewer evaluates, so a baked frame is the viewer's displaced
// density. No OpenVDB here (write_vdb_frame lives in src/io/vdb_frame.cpp); docs/motion.md.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cloudgen/export_options.h"
#include "cloudgen/motion.h"
#include "cloudgen/output.h"
#include "cloudgen/volume.h"

namespace cloudgen {

/// Highest frame number --frames accepts, and the most frames one run bakes.
inline constexpr int64_t kMaxFrameNumber = 9999999;
inline constexpr int64_t kMaxSequenceFrames = 100000;

/// Frames first..last, both included.
struct FrameRange {
  int64_t first = 0, last = 0;
  int64_t count() const { return last - first + 1; }
};
/// "A:B" (0 <= A <= B <= kMaxFrameNumber, at most kMaxSequenceFrames frames) or "A" (one frame).
/// InputError naming `flag`, the value and the allowed range otherwise.
FrameRange parse_frames(const std::string& text, const std::string& flag = "--frames");
/// Frames per second from text: a finite number in (0, 1000]; InputError naming `flag` otherwise.
double parse_fps(const std::string& text, const std::string& flag = "--fps");

/// Blender's volume-sequence naming: the last run of '#' in the file name (not the folder) is
/// replaced by the frame number, zero-padded to the run's length ("cloud_####.vdb", 7 ->
/// "cloud_0007.vdb"; longer numbers keep every digit). A path without '#' is returned unchanged.
std::string frame_path(const std::string& pattern, int64_t frame);
bool has_frame_pattern(const std::string& path);

/// The box the height fraction is measured in (the static volume's, y up, metres) and its tiling.
struct MotionBox {
  std::array<uint32_t, 3> dims{{0, 0, 0}};
  double voxel_size = 1;
  std::array<double, 3> origin{{0, 0, 0}};
  bool tiles_xz = false;
  double min_y() const { return origin[1]; }
  double height() const { return dims[1] * voxel_size; }
};
MotionBox motion_box(const Volume& v);

/// h(p) = (p.y - box.min_y) / box.height (motion_displacement clamps it to [0, 1]).
inline double height_fraction(const MotionBox& b, double y) { return (y - b.min_y()) / b.height(); }

/// dD/dt (m/s, y-up world) by a central difference of motion_displacement over +-kVelocityStep s.
inline constexpr double kVelocityStep = 1e-4;
glm::dvec3 motion_velocity(const MotionParams& m, double t, double h);

/// --loop: the motion snapped so frame last + 1 equals frame first (duration = count / fps s):
/// the flow speed to a whole number of cycles (at least one), the wind (tileable volumes) to a
/// whole number of tiles along x and along z. A box (non-tiling) volume with wind, or any wind
/// with motion.wind_shear > 0 (heights travel different distances, so no speed brings them all
/// back to a whole tile), is an InputError naming the key. `notes` says what was changed.
MotionParams loop_motion(const MotionParams& m, double duration_s, const MotionBox& box,
                         std::vector<std::string>* notes = nullptr);

/// The voxels of a frame in the static volume's index space, [lo, hi) per axis: the static box
/// for tileable volumes; for box volumes, every voxel whose displaced position lands inside the
/// static box (the cloud's box follows the wind). Depends only on the box, motion and time.
struct FrameBox {
  std::array<int64_t, 3> lo{{0, 0, 0}}, hi{{0, 0, 0}};
  uint64_t voxels() const;
};
FrameBox frame_box(const MotionBox& box, const MotionParams& m, double t);

/// One baked frame: `volume` holds the displaced channels over frame_box (its origin shifted by
/// whole voxels from the static one; no occupancy), `row_velocity[j]` the velocity (m/s, y-up
/// world) of the frame's row j, and what the metadata records.
struct MotionFrame {
  Volume volume;
  std::vector<glm::dvec3> row_velocity;
  int64_t frame = 0;
  double time = 0, fps = 0;
  bool loop = false;
  FrameRange range;
  MotionParams motion;
  MotionBox box;
};

/// The static channel `ch` of `v` at world point q, as the viewer reads its texture: zero outside
/// the box (above and below it always, beyond x/z only for non-tiling volumes), inside it trilinear
/// between voxel centres with x and z wrapped for tiling volumes and indices clamped otherwise.
double sample_static(const Volume& v, const std::vector<float>& ch, const glm::dvec3& q);

/// Frame `frame` at t = frame / fps: value(p) = static(p - D(h(p), t)) at every voxel centre p of
/// frame_box, for density and every detail channel present. `threads` workers (0 = all); the
/// bytes do not depend on it. D = 0 (t = 0, or no motion) gives the static channels exactly.
MotionFrame bake_frame(const Volume& stat, const MotionParams& m, int64_t frame, double fps, int threads = 0);

/// Bytes a frame's dense channels and its VDB trees may need at most (for --max-memory).
uint64_t frame_memory_estimate(const MotionBox& box, const MotionParams& m, const FrameRange& r, double fps,
                               int channels);

/// Stages the frame as a .vdb in `batch`: the grids write_vdb writes, plus a Vec3s grid
/// "velocity" (m/s, world space of the file, on the density's active voxels) and per-frame
/// metadata on the density grid (docs/motion.md lists the keys).
void write_vdb_frame(const MotionFrame& f, const std::string& path, const ExportOptions& o, OutputBatch& batch);

}  // namespace cloudgen
