// Probes for tests and measurements: the renderers' counters, and the shared shader maths
// evaluated one value at a time in double precision (the same GLSL text the shaders compile).
#pragma once
#include <cstdint>
#include <vector>

#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

/// What a GlRenderer has built and drawn so far: each count rises once per rebuild, so a test can
/// tell a cache that holds from one that rebuilds every frame.
struct RendererStats {
  /// Light volume builds (render.light_volume): once per change of the sun, the volume or a
  /// lighting key, never for a camera move alone.
  int light_volume_builds = 0;
  /// Ground shadow map builds (render.shadow_map): once per change of the sun, the volume, the time
  /// (moving clouds) or a lighting key, never for a camera move alone.
  int shadow_map_builds = 0;
  /// Ground pass draws. A held temporal frame (render.temporal, nothing moved, no table the ground
  /// reads rebuilt) keeps the last frame's ground instead (unless set_ground_reuse(false)).
  int ground_draws = 0;
  /// Builds of the camera's air LUT (render.air_lut).
  int air_lut_builds = 0;
  /// Distinct GL programs linked (render.compiled_modes: one set per set of modes seen).
  int program_count = 0;
  /// Solves of the diffusion volume (render.ms_volume).
  int ms_volume_builds = 0;
  /// Whether the NanoVDB grids (and their leaf page table) are on the GPU: only once a frame has
  /// read them (render.nanovdb_lookup=table or accessor, or a refused atlas); the brick atlas, the
  /// default, leaves them on the CPU.
  bool nano_grids_on_gpu = false;
};

/// Mean radiance (linear HDR) of `spp` paths along one camera-relative unit ray (for tests).
glm::dvec3 pathtrace_ray(const PreparedVolume& vol, const FrameSetup& frame, const glm::dvec3& rd, int spp,
                         uint32_t seed = 1);
/// The optical depth toward the sun at camera-relative p: the per-sample light march, or with
/// `light_volume` (from build_light_volume_cpu) its trilinear lookup. For tests and measurements.
double reference_light_optical_depth(const PreparedVolume& vol, const ref::CloudParams& params, glm::dvec3 p,
                                     const std::vector<double>* light_volume = nullptr);
/// The clouds' shadow at the camera-relative ground point p: the march the ground pass runs per
/// pixel, or with `shadow_map` (from build_shadow_map_cpu) its bilinear lookup. For tests.
double reference_ground_shadow(const PreparedVolume& vol, const FrameSetup& frame, glm::dvec3 p,
                               const std::vector<double>* shadow_map = nullptr);

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

/// The atmosphere LUTs' size-against-error study (docs/notes/sky.md).
/// The transmittance LUT at half (size_index 0), the shipped (1) or double (2)
/// the 256x64 size, computed by the same header, looked up at each (r, mu); `size` receives W x H.
std::vector<glm::dvec3> transmittance_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                      const std::vector<glm::dvec2>& r_mu, glm::ivec2& size);

/// The same study for the multiple-scattering LUT: Psi_ms at (r, mu_s) through the LUT at 16 x 16
/// (size_index 0), the shipped 32 x 32 (1) or 64 x 64 (2); `size` receives the edge.
std::vector<glm::dvec3> multiple_scattering_lookups_at_size(const ref::AtmosphereParams& p, int size_index,
                                                            const std::vector<glm::dvec2>& r_mu_s, int& size);

/// A sky ray for the scattering-LUT study: from `altitude` (m above the ground) along unit `view`
/// (zenith +y) with the sun along unit `sun`, over the first `t_max` metres (CV_NO_HIT: to the top
/// of the atmosphere or the ground).
struct SkyQuery {
  double altitude = 0;
  glm::dvec3 view{0, 1, 0}, sun{0, 1, 0};
  double t_max = CV_NO_HIT;
};
/// Bruneton's 4D scattering LUT (atmosphere.glsl, atmosphere_scattering_lut) on the CPU at half
/// Bruneton's 256 x 128 x 32 (size_index 0: 128 x 64 x 16), his size (1), the shipped size (2: his
/// with twice the mu_s texels, 512 x 128 x 32) or double his (3: 512 x 256 x 64), 8 nu slices
/// each, over the other LUTs of `luts`: the sky's radiance of each query for unit solar
/// irradiance, to the top of the atmosphere or the ground. Texels are computed as lookups read
/// them; `size` receives the 3D texture's size and `texels_computed` how many were computed.
std::vector<glm::dvec3> scattering_lookups_at_size(const AtmosphereLuts& luts, int size_index,
                                                   const std::vector<SkyQuery>& queries, glm::ivec3& size,
                                                   size_t* texels_computed = nullptr);
/// The scattering LUT's parametrisation checked at every texel of the shipped size: the texel's
/// (r, mu, mu_s, nu) mapped back to texture coordinates lands this far (in texels) from the
/// texel's centre, per axis (nu, mu_s, mu, r; nu where the texel's nu is not clamped to what its mu
/// and mu_s allow; mu except the ground rays at r = bottom, which all have length 0).
glm::dvec4 scattering_parametrisation_roundtrip(const AtmosphereLuts& luts);

}  // namespace cloudviewer
