// The OpenGL 4.5 renderer: one FrameSetup in, the frame's images out; needs a current context
// (headless_context.h or a GLFW window).
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cloudviewer/frame_images.h"
#include "cloudviewer/ms_diffusion.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/shader_source.h"
#include "cloudviewer/testing.h"

namespace cloudviewer {

struct GpuTimings {
  double ground_ms = 0, cloud_ms = 0, post_ms = 0, total_ms = 0;
  double atmosphere_ms = 0;  ///< the atmosphere LUT passes and the air LUT (0 unless an atmosphere.* key, the sun or the camera altitude changed)
  double light_volume_ms = 0;  ///< the light volume's rebuild (0 unless the sun, volume or a lighting key changed)
  double shadow_map_ms = 0;  ///< the ground shadow map's rebuild (0 unless the sun, volume, time or a lighting key changed)
  /// Wall-clock time spent compiling and linking GL programs since the previous render() (the
  /// constructor's and reload_shaders' count toward the next frame), and how many were linked: 0
  /// unless the renderer needed a program it had not linked (the first frame, a new set of
  /// render.compiled_modes, a new NanoVDB lookup). Not in total_ms (GPU time).
  double compile_ms = 0;
  int programs_linked = 0;
  std::vector<std::pair<std::string, double>> passes;  ///< every pass that drew this frame, in order, ms
};

/// OpenGL 4.5 renderer; needs a current context (EGL headless or a GLFW window).
class GlRenderer {
 public:
  explicit GlRenderer(ShaderSource shaders);
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  /// Uploads the volume textures and the Mie table.
  void set_volume(const PreparedVolume& vol);
  /// Uploads only the distance field of the volume set_volume took (fit_distance_field rebuilt it:
  /// the same cells); the lighting caches and the temporal history stay.
  void set_distance_field(const PreparedVolume& vol);
  /// Recompiles every program (shader hot reload); the next frame recomputes every cached table
  /// (LUTs, light volume, shadow map) and drops the temporal history. Throws ShaderError, keeping
  /// the old programs and caches.
  void reload_shaders();
  /// Renders into internal targets; `timings` from GPU timer queries (of this frame).
  void render(const FrameSetup& frame, GpuTimings* timings = nullptr);
  /// Reads the last frame back.
  FrameImages read_back();
  /// Reads one attachment of an internal 2D target as RGBA floats (a one-channel target in R), for
  /// tests and debugging: "cloud_layer" attachment 0 after render() is the resolved temporal
  /// cloud layer (L, T) that the next frame reprojects. Throws GlError for an unknown name, a 3D
  /// target or an attachment it does not have.
  Image read_target(const std::string& name, int attachment = 0);
  /// Blits the display image into the default framebuffer (window mode).
  void present(int window_width, int window_height);
  /// Blits `display` (display values, as FrameImages::display; row 0 at the bottom, as read_back's)
  /// into the default framebuffer in place of the frame: the window's path-traced reference.
  void present_image(const Image& display, int window_width, int window_height);
  /// Reads the default framebuffer's back buffer (what present() drew), 8-bit display values.
  Image read_window(int window_width, int window_height);
  std::string renderer_string() const;
  /// Computes the transmittance LUT on the GPU (if `atmosphere` differs from the last) and reads it
  /// back on the --dump-lut grid (kDumpAltitudes x kDumpMus, altitude-major) through the shaders'
  /// lookup; rays that hit the ground hold 0. `precompute_ms`: GPU time of the LUT passes (0 when
  /// nothing changed). Works before set_volume.
  std::vector<glm::vec3> transmittance_dump(const AtmosphereSettings& atmosphere, double* precompute_ms = nullptr);
  /// What the renderer has built and drawn so far (testing.h's RendererStats): the counters that
  /// show a cache holds, for tests, --stats and the bench.
  RendererStats stats() const;
  /// Off: the ground pass draws every frame, even a held temporal frame (tests and benchmarks
  /// compare the two).
  void set_ground_reuse(bool on);
  /// The last diffusion solve's iterations, convergence and energy balance (render.ms_volume; its
  /// fluence is on the GPU: empty here).
  MsDiffusionResult last_ms_solve() const;
  /// How many times the atmosphere LUT pass `pass` ("atmosphere_scattering", ...) has run: once per
  /// change of an atmosphere.* key while a frame needs it (the 4D scattering LUT: with
  /// render.sky_lut), never for a sun, camera or viewport change.
  int lut_computations(const std::string& pass) const;
  /// The passes in execution order (their names label GpuTimings::passes).
  std::vector<std::string> pass_names() const;
  /// The driver's std140 layout of the cloud block: its size in bytes, and a member's byte offset
  /// ("volume_min_m"; -1 when the driver does not list it). For the layout test.
  int cloud_block_size() const;
  int cloud_block_offset(const std::string& member) const;
  /// The same for the atmosphere block as the cloud pass sees it (its size, a member's offset).
  int atmosphere_block_size() const;
  int atmosphere_block_offset(const std::string& member) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cloudviewer
