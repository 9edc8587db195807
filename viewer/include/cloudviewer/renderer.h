// The two renderers. Both take a FrameSetup and return the display image (tone-mapped, sRGB
// encoded, [0,1]) and the linear HDR image (after bloom, before exposure).
#pragma once
#include <memory>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cloudviewer/image.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

struct FrameImages {
  Image display;  ///< sRGB-encoded tone-mapped values in [0,1]
  Image linear;   ///< scene-linear HDR radiance (output=transmittance: T in RGB)
};

struct GpuTimings {
  double ground_ms = 0, cloud_ms = 0, post_ms = 0, total_ms = 0;
  double atmosphere_ms = 0;  ///< the atmosphere LUT passes (0 unless an atmosphere.* key changed)
  std::vector<std::pair<std::string, double>> passes;  ///< every pass in order, ms
};

/// Where the GLSL comes from: the copies embedded at build time, or a directory (`--shader-dir`).
class ShaderSource {
 public:
  explicit ShaderSource(std::string dir = {}) : dir_(std::move(dir)) {}
  /// Text of one file; throws InputError when it does not exist.
  std::string load(const std::string& name) const;
  /// The file with every `#include "x"` expanded once and `#line` directives so compile logs map
  /// back to files. `files` receives the file name of each source-string number.
  std::string expand(const std::string& name, std::vector<std::string>& files) const;
  const std::string& dir() const { return dir_; }
  /// Replaces one file's text (before --shader-dir and the embedded copies): the renderer's
  /// compile-time switches (nanovdb_storage.glsl).
  void set_override(const std::string& name, std::string text) { overrides_[name] = std::move(text); }

 private:
  void expand_into(const std::string& name, std::vector<std::string>& files, std::string& out,
                   std::vector<std::string>& stack) const;
  std::string dir_;
  std::map<std::string, std::string> overrides_;
};

/// Names of the embedded shader files.
std::vector<std::string> embedded_shader_names();

/// Compiles one stage; on failure throws ShaderError with "FILE:LINE: log" (file and line mapped
/// through the #line directives) for the first error. Needs a current GL context.
unsigned compile_shader_stage(unsigned stage, const ShaderSource& src, const std::string& name);

/// OpenGL 4.5 renderer; needs a current context (EGL headless or a GLFW window).
class GlRenderer {
 public:
  explicit GlRenderer(ShaderSource shaders);
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  /// Uploads the volume textures and the Mie table.
  void set_volume(const PreparedVolume& vol);
  /// Recompiles every program (shader hot reload). Throws ShaderError, keeping the old programs.
  void reload_shaders();
  /// Renders into internal targets; `timings` from GPU timer queries (of this frame).
  void render(const FrameSetup& frame, GpuTimings* timings = nullptr);
  /// Reads the last frame back.
  FrameImages read_back();
  /// Blits the display image into the default framebuffer (window mode).
  void present(int window_width, int window_height);
  /// Reads the default framebuffer's back buffer (what present() drew), 8-bit display values.
  Image read_window(int window_width, int window_height);
  std::string renderer_string() const;
  /// Computes the transmittance LUT on the GPU (if `atmosphere` differs from the last) and reads it
  /// back on the --dump-lut grid (kDumpAltitudes x kDumpMus, altitude-major) through the shaders'
  /// lookup; rays that hit the ground hold 0. `precompute_ms`: GPU time of the LUT passes (0 when
  /// nothing changed). Works before set_volume.
  std::vector<glm::vec3> transmittance_dump(const AtmosphereSettings& atmosphere, double* precompute_ms = nullptr);
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

/// Double-precision CPU reference of the same passes, evaluated with TBB over pixels.
FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame);

/// The shared header's phase function (1/sr) evaluated in double precision (for tests and docs).
double reference_phase(PhaseMode mode, double g, double cos_theta);
/// The shared cloud-type height gradient (cloudgen/cloud_type.glsl) as the CPU reference compiles
/// it: normalised layer height h in [0, 1], type 0 stratus .. 0.5 cumulus .. 1 cumulonimbus.
double reference_cloud_type_gradient(double h, double type);

/// A headless OpenGL 4.5 core context: EGL device platform when a hardware device is present
/// (NVIDIA), Mesa surfaceless otherwise (CLOUDVIEWER_EGL=device|surfaceless forces one). Throws
/// GlError when none can be created.
class HeadlessContext {
 public:
  HeadlessContext();
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;
  const std::string& description() const { return description_; }
  void make_current();

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string description_;
};

}  // namespace cloudviewer
