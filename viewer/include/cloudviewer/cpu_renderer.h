// The CPU renderers: the double-precision reference of the GL passes and the path tracer, the
// ground truth for the lighting. src/cpu/cpu_renderer.cpp.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "cloudviewer/frame_images.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

/// Double-precision CPU reference of the same passes, evaluated with TBB over pixels.
FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame);

/// The path tracer (`--backend pathtrace`, src/cpu/cpu_renderer.cpp): the ground truth for the
/// lighting. Same medium, sun, ambient sky and background as render_cpu; every order of scattering
/// by delta tracking with next-event estimation of the sun. Deterministic at any thread count.
/// Paths summed over several calls (the window's progressive reference): per pixel the sum of the
/// paths' scene-linear radiance (RGB, before bloom) and how many paths were summed.
struct PathTraceSum {
  int width = 0, height = 0;
  std::vector<double> rgb;  ///< width * height * 3, x fastest
  int64_t paths = 0;        ///< per pixel
};

struct PathTraceOptions {
  int spp = 64;                 ///< paths per pixel
  int max_scatterings = 4096;   ///< per path (albedo-1 clouds scatter hundreds of times)
  uint32_t seed = 1;
  std::function<void(int rows_done, int rows)> progress;  ///< called from worker threads
  /// When set: per pixel, the standard error of the mean (RGB; sample standard deviation of the
  /// paths / sqrt(spp)) of the scene-linear radiance before bloom, so a comparison can tell the
  /// path tracer's noise from a bias. Alpha 1.
  Image* standard_error = nullptr;
  /// Paths first_sample .. first_sample + spp - 1 of each pixel's stream: calls over consecutive
  /// ranges trace the paths one call of all of them traces.
  int first_sample = 0;
  /// When set: this call's paths are added to it (started again when the size differs) and the
  /// images are those of all the paths it holds; summed over calls with consecutive first_sample,
  /// the image of one call with their spp but for the rounding of the sums' order.
  PathTraceSum* sum = nullptr;
  /// When set and true: the call stops within a row and returns empty images, `sum` untouched.
  const std::atomic<bool>* cancel = nullptr;
};
FrameImages render_pathtrace(const PreparedVolume& vol, const FrameSetup& frame, const PathTraceOptions& o);
/// The ground shadow map (render.shadow_map) as the CPU reference builds it: the clouds'
/// transmittance toward the sun at every texel centre of the frame's shadow_map_nx x shadow_map_nz
/// grid (lighting.glsl shadow_map_position), double precision, x fastest.
std::vector<double> build_shadow_map_cpu(const PreparedVolume& vol, const FrameSetup& frame);
/// The light volume (render.light_volume) as the CPU reference builds it: light_optical_depth at
/// every texel centre of a params.light_volume_dims grid over the march box (the volume's box while
/// still), double precision, x fastest. Moving clouds need `frame` (its motion table).
std::vector<double> build_light_volume_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                           const FrameSetup* frame = nullptr);

}  // namespace cloudviewer
