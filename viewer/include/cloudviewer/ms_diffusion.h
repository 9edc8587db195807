// Multiple scattering by flux-limited diffusion (render.ms_volume): the grid, the solver and the
// texels both renderers look up. src/cpu/ms_diffusion.cpp.
#pragma once
#include <memory>
#include <vector>

#include "cloudviewer/mie_table.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

/// Multiple scattering by flux-limited diffusion (render.ms_volume, src/cpu/ms_diffusion.cpp): the
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

/// The frame's diffusion grid (params.ms_volume_dims over the box, vacuum beyond it), arrays zeroed.
MsDiffusionGrid ms_diffusion_grid(const ref::CloudParams& params);
/// The diffusion volume as both renderers build it: ms_volume_source (lighting.glsl) per cell in
/// double precision (`light_volume`: the light volume's texels when params.light_volume_on), then
/// solve_ms_diffusion with the frame's albedo and its phase function's asymmetry.
MsDiffusionGrid build_ms_source_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                    const std::vector<double>* light_volume);
/// `mie`: render.phase=mie's table (FrameSetup::mie; empty: the computed one).
MsDiffusionOptions ms_diffusion_options(const ref::CloudParams& params,
                                        const std::shared_ptr<const MiePhaseTable>& mie = nullptr);
/// The asymmetry parameter <cos theta> of the frame's phase function (green channel), integrated
/// numerically; `mie` as for ms_diffusion_options.
double phase_asymmetry(const ref::CloudParams& params, const std::shared_ptr<const MiePhaseTable>& mie = nullptr);

}  // namespace cloudviewer
