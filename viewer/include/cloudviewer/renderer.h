// The two renderers. Both take a FrameSetup and return the display image (tone-mapped, sRGB
// encoded, [0,1]) and the linear HDR image (after bloom, before exposure).
#pragma once
#include <functional>
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
  /// compile-time switches (nanovdb_storage.glsl, modes.glsl).
  void set_override(const std::string& name, std::string text) { overrides_[name] = std::move(text); }
  void clear_override(const std::string& name) { overrides_.erase(name); }

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

/// Multiple scattering by flux-limited diffusion (render.ms_volume, src/ms_diffusion.cpp): the
/// inputs on a coarse grid over the box, x fastest, per unit sun irradiance.
struct MsDiffusionGrid {
  glm::ivec3 dims{0};
  glm::dvec3 cell_m{0.0};          ///< cell edge per axis, metres
  bool tiles_xz = false;           ///< x and z wrap (else every face of the box sees vacuum)
  std::vector<double> sigma_t;     ///< each cell's mean extinction, 1/m
  std::vector<double> source;      ///< each cell's mean sigma_t * T_sun, 1/m (times the albedo: the source)
};
struct MsDiffusionOptions {
  double albedo = 1;               ///< sigma_s / sigma_t
  double asymmetry = 0;            ///< the phase function's mean cosine (similarity: sigma_tr = sigma_a + sigma_s (1 - g))
  int max_iterations = 3000;
  double tolerance = 1e-5;         ///< stop when an iteration changes no cell by more than this x the largest fluence
  double relaxation = 1.8;         ///< successive over-relaxation factor, in (0, 2)
};
struct MsDiffusionResult {
  std::vector<double> fluence;     ///< phi per cell: fluence of the light scattered at least once, per unit sun irradiance
  std::vector<glm::dvec3> flux;    ///< its net flux F = -D grad phi per cell (|F| <= phi)
  int iterations = 0;               ///< on this grid
  int coarse_iterations = 0;        ///< on the coarser grids that gave its starting point (nested iteration)
  bool converged = false;
  double change = 0;               ///< the last iteration's largest relative change
  double source_power = 0, absorbed_power = 0, leaked_power = 0;  ///< energy balance, per unit irradiance (m^2)
  double seconds = 0;              ///< wall time of the solve, coarser grids included
};
MsDiffusionResult solve_ms_diffusion(const MsDiffusionGrid& grid, const MsDiffusionOptions& options);
/// The texels both renderers look up (lighting.glsl ms_volume_radiance): phi and 3 g F per cell,
/// g the phase function's asymmetry, so the in-scattered diffuse radiance toward w is
/// (phi + 3 g F . w) / 4 pi (the P1 radiance phi / 4 pi + 3 F . w' / 4 pi through the phase function).
std::vector<glm::dvec4> ms_volume_texels(const MsDiffusionResult& solve, double asymmetry);

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
  /// Reads the default framebuffer's back buffer (what present() drew), 8-bit display values.
  Image read_window(int window_width, int window_height);
  std::string renderer_string() const;
  /// Computes the transmittance LUT on the GPU (if `atmosphere` differs from the last) and reads it
  /// back on the --dump-lut grid (kDumpAltitudes x kDumpMus, altitude-major) through the shaders'
  /// lookup; rays that hit the ground hold 0. `precompute_ms`: GPU time of the LUT passes (0 when
  /// nothing changed). Works before set_volume.
  std::vector<glm::vec3> transmittance_dump(const AtmosphereSettings& atmosphere, double* precompute_ms = nullptr);
  /// How many times the light volume has been built (render.light_volume): once per change of the
  /// sun, the volume or a lighting key, never for a camera move alone.
  int light_volume_builds() const;
  /// How many times the ground shadow map has been built (render.shadow_map): once per change of
  /// the sun, the volume, the time (moving clouds) or a lighting key, never for a camera move alone.
  int shadow_map_builds() const;
  /// How many times the ground pass has drawn. A held temporal frame (render.temporal, nothing
  /// moved since the last frame, no table the ground reads rebuilt) keeps the last frame's ground
  /// instead; set_ground_reuse(false) draws it every frame (tests and benchmarks compare the two).
  int ground_draws() const;
  void set_ground_reuse(bool on);
  /// Whether the NanoVDB grids (and their leaf page table) are on the GPU: only once a frame has
  /// read them (render.nanovdb_lookup=table or accessor, or an atlas that was refused); the brick
  /// atlas, the default, leaves them on the CPU.
  bool nano_grids_on_gpu() const;
  /// How many times the camera's air LUT (render.air_lut) has been built.
  int air_lut_builds() const;
  /// Distinct GL programs linked so far (render.compiled_modes: one set per set of modes seen).
  int program_count() const;
  /// How many times the diffusion volume has been solved (render.ms_volume), and the last solve's
  /// iterations, convergence and energy balance (its fluence is on the GPU: empty here).
  int ms_volume_builds() const;
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

/// Double-precision CPU reference of the same passes, evaluated with TBB over pixels.
FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame);

/// The path tracer (`--backend pathtrace`, src/cpu_renderer.cpp): the ground truth for the
/// lighting. Same medium, sun, ambient sky and background as render_cpu; every order of scattering
/// by delta tracking with next-event estimation of the sun. Deterministic at any thread count.
struct PathTraceOptions {
  int spp = 64;                 ///< paths per pixel
  int max_scatterings = 4096;   ///< per path (albedo-1 clouds scatter hundreds of times)
  uint32_t seed = 1;
  std::function<void(int rows_done, int rows)> progress;  ///< called from worker threads
  /// When set: per pixel, the standard error of the mean (RGB; sample standard deviation of the
  /// paths / sqrt(spp)) of the scene-linear radiance before bloom, so a comparison can tell the
  /// path tracer's noise from a bias. Alpha 1.
  Image* standard_error = nullptr;
};
FrameImages render_pathtrace(const PreparedVolume& vol, const FrameSetup& frame, const PathTraceOptions& o);
/// Mean radiance (linear HDR) of `spp` paths along one camera-relative unit ray (for tests).
glm::dvec3 pathtrace_ray(const PreparedVolume& vol, const FrameSetup& frame, const glm::dvec3& rd, int spp,
                         uint32_t seed = 1);
/// The ground shadow map (render.shadow_map) as the CPU reference builds it: the clouds'
/// transmittance toward the sun at every texel centre of the frame's shadow_map_nx x shadow_map_nz
/// grid (lighting.glsl shadow_map_position), double precision, x fastest.
std::vector<double> build_shadow_map_cpu(const PreparedVolume& vol, const FrameSetup& frame);
/// The light volume (render.light_volume) as the CPU reference builds it: light_optical_depth at
/// every texel centre of a params.light_volume_dims grid over the march box (the volume's box while
/// still), double precision, x fastest. Moving clouds need `frame` (its motion table).
std::vector<double> build_light_volume_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                           const FrameSetup* frame = nullptr);
/// The optical depth toward the sun at camera-relative p: the per-sample light march, or with
/// `light_volume` (from build_light_volume_cpu) its trilinear lookup. For tests and measurements.
double reference_light_optical_depth(const PreparedVolume& vol, const ref::CloudParams& params, glm::dvec3 p,
                                     const std::vector<double>* light_volume = nullptr);
/// The clouds' shadow at the camera-relative ground point p: the march the ground pass runs per
/// pixel, or with `shadow_map` (from build_shadow_map_cpu) its bilinear lookup. For tests.
double reference_ground_shadow(const PreparedVolume& vol, const FrameSetup& frame, glm::dvec3 p,
                               const std::vector<double>* shadow_map = nullptr);

/// The frame's diffusion grid (params.ms_volume_dims over the box, vacuum beyond it), arrays zeroed.
MsDiffusionGrid ms_diffusion_grid(const ref::CloudParams& params);
/// The diffusion volume as both renderers build it: ms_volume_source (lighting.glsl) per cell in
/// double precision (`light_volume`: the light volume's texels when params.light_volume_on), then
/// solve_ms_diffusion with the frame's albedo and its phase function's asymmetry.
MsDiffusionGrid build_ms_source_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                    const std::vector<double>* light_volume);
MsDiffusionOptions ms_diffusion_options(const ref::CloudParams& params);
/// The asymmetry parameter <cos theta> of the frame's phase function (green channel), integrated numerically.
double phase_asymmetry(const ref::CloudParams& params);

/// The shared header's phase function (1/sr) evaluated in double precision (for tests and docs).
double reference_phase(PhaseMode mode, double g, double cos_theta);
/// The same for every render.phase mode and its parameters (the Mie table's green channel).
double reference_phase(const RenderSettings& s, double cos_theta);
/// Per colour channel, as the marcher uses it (phase_function_rgb: the Mie table's 650, 550 and
/// 450 nm; an analytic lobe in all three).
glm::dvec3 reference_phase_rgb(const RenderSettings& s, double cos_theta);
/// temporal.glsl's cross matrix M[y][x] (seed 003) and the 4x4 block position frame `frame` marches,
/// as the renderer and the tests use them (the same text the shaders compile).
int reference_cross_matrix(int x, int y);
glm::ivec2 reference_cross_matrix_offset(int frame);
/// temporal.glsl's air as temporal upsampling carries it from a sparse pixel to another: the air
/// toward distance t_k (in-scattered light, transmittance) turned into extinction and
/// in-scattering per metre (air_coefficients), then evaluated toward distance t (air_over_distance).
void reference_air_carried(const glm::dvec3& inscattered, const glm::dvec3& transmittance, double t_k, double t,
                           glm::dvec3& inscattered_t, glm::dvec3& transmittance_t);
/// medium.glsl's cloud_density at camera-relative p (metres) with the frame's parameters, motion
/// included, in double precision (for tests: the moving volume against the static one).
double reference_density(const PreparedVolume& vol, const FrameSetup& frame, const glm::dvec3& p);
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
