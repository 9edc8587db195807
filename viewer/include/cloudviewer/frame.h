// One frame's set-up: the parameter block both renderers consume (params.h), built from the
// volume, the settings, the camera and the sun. No OpenGL here. src/scene/frame.cpp.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cloudviewer/camera.h"
#include "cloudviewer/coverage_map.h"
#include "cloudviewer/mie_table.h"
#include "cloudviewer/params.h"
#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudviewer {

/// The ground shadow map (render.shadow_map) has at most this many texels per side: make_frame
/// doubles the texel until it fits.
constexpr int kMaxShadowMapSide = 2048;
/// The light volume (render.light_volume) never has more texels than this: make_frame doubles
/// render.light_volume_scale until it fits.
constexpr int kMaxLightVolumeTexels = 1 << 22;
/// The diffusion volume (render.ms_volume) never has more cells than this (64^3): make_frame
/// doubles render.ms_volume_scale until it fits.
constexpr int kMaxMsVolumeCells = 1 << 18;

struct FrameSetup {
  int width = 0, height = 0;
  Camera camera;
  Sun sun;
  RenderSettings settings;
  ref::CloudParams params;   ///< double values, already rounded to float (what the GPU sees)
  glm::dmat4 view_proj;      ///< camera-relative
  glm::dmat4 inv_view_proj;  ///< rounded to float, like the GPU's
  double ground_half_extent = 0;
  /// Motion table (medium.glsl): D(h) at CV_MOTION_LUT_SIZE heights for this frame's time (row 0)
  /// and, for temporal reprojection, the previous frame's (row 1; the GL renderer fills it in).
  /// Empty when the clouds are still.
  std::vector<glm::dvec3> motion_table;
  /// Moving clouds in box mode: the occupancy of the march box at this time, params.moved_occ_dims
  /// cells of params.moved_occ_cell_m from params.march_min_m (x fastest, 0 or 1), which both
  /// renderers' occupied() reads instead of the volume's grid (medium.glsl). Empty otherwise, and
  /// when no call reads occupied() (distance skipping without render.occupancy_light: make_frame).
  std::vector<uint8_t> moved_occupancy;
  /// render.phase=mie: the table this frame reads (mie_table_of its settings); empty otherwise.
  std::shared_ptr<const MiePhaseTable> mie;
  /// Layer mode: the coverage map this frame reads (CV_COVERAGE_MAP_SIZE^2 RG texels); empty in box mode.
  std::shared_ptr<const std::vector<float>> coverage;
};

/// motion_displacement (cloudgen/motion.glsl) at CV_MOTION_LUT_SIZE evenly spaced heights in
/// [0, 1] at time t: one row of FrameSetup::motion_table.
std::vector<glm::dvec3> motion_table_row(const RenderSettings& s, double t);

/// The phase function's slots of the parameter block (render.phase and its parameters; the HG +
/// Draine fit evaluated at render.droplet_diameter).
void set_phase_params(ref::CloudParams& p, const RenderSettings& s);

/// Fills the parameter block from the volume, settings, camera and sun.
FrameSetup make_frame(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam,
                      const Sun& sun, int width, int height);

/// The window's frame: make_frame with `s`, or, when the volume refuses them (InputError: a panel
/// choice such as render.mode=layer on a volume that does not tile, render.skipping=tree on the
/// dense path), `s` put back to `good` (the last settings a frame took; its time and frame index
/// kept) with the refusal in `refused`. `good` follows every frame that succeeds. Throws when
/// `good` is refused too (the command line's own settings).
FrameSetup make_frame_or_keep(const PreparedVolume& vol, RenderSettings& s, RenderSettings& good, const Camera& cam,
                              const Sun& sun, int width, int height, std::string& refused);

}  // namespace cloudviewer
