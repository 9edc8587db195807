// Parameter packing: the CloudParams block both renderers consume, from the volume, settings,
// camera and sun.
#include <algorithm>
#include <cmath>

#include "cloudgen/view.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

FrameSetup make_frame(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam,
                      const Sun& sun, int width, int height) {
  FrameSetup f;
  f.width = width;
  f.height = height;
  f.camera = cam;
  f.sun = sun;
  f.settings = s;
  const bool layer = s.mode == PlaceMode::Layer;
  if (layer && !vol.tiles)
    throw InputError("render.mode=layer repeats the texture over the sky, so it needs a tileable volume "
                     "(x and z wrap; cloudgen presets and synthetic:noise tile, this input does not)");
  glm::dvec3 size = vol.size();
  glm::dvec2 alt = layer ? layer_altitudes(vol, s) : glm::dvec2(0.0);
  if (layer) size.y = alt.y - alt.x;  // the texture's height stretches over the layer
  glm::dvec3 voxel = size / glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2]);
  double min_voxel = std::min(voxel.x, std::min(voxel.y, voxel.z));
  double max_extent = std::max(size.x, std::max(size.y, size.z));
  double dt = max_extent / s.steps;
  double cell_m = vol.occ_cell * min_voxel;
  // Large step: k small steps, just under one coarse cell less half a voxel. Why that is safe with
  // any padding >= 1: non-zero density (trilinear reaches half a voxel past a non-empty cell) lies
  // within half a voxel of a non-empty cell, and every unoccupied cell is at least one full cell
  // away from a non-empty one, so a segment shorter than (cell - voxel/2) that starts and ends in
  // unoccupied cells cannot touch density. The march checks both ends of every large step.
  // In layer mode cells are measured in the smallest world voxel edge (the texture may be stretched
  // vertically); the Earth's curvature bends a large step by d^2/2R, far below half a voxel.
  int k = std::max(1, int(std::floor(0.999 * (cell_m - 0.5 * min_voxel) / dt)));
  double diag = glm::length(size);
  ref::CloudParams& p = f.params;
  p = ref::CloudParams{};  // zero: layer fields stay 0 in box mode
  p.volume_min_m = vol.origin - cam.eye;
  p.voxel_size_m = vol.voxel_size;
  p.volume_size_m = size;  // box mode only
  p.tiles_xz = vol.tiles || layer ? 1.0 : 0.0;
  p.volume_dims = glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2]);
  p.has_detail = vol.has_detail ? 1.0 : 0.0;
  p.occ_dims = glm::dvec3(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  p.occ_cell_voxels = vol.occ_cell;
  p.sun_dir = sun.direction();
  p.sun_radiance = s.sun_intensity;
  p.sun_color = glm::dvec3(1.0, 0.96, 0.9);
  p.ambient_scale = s.ambient;
  p.ambient_color = glm::dvec3(0.30, 0.38, 0.52);
  p.albedo = s.albedo;
  // Auto values follow the voxel size, not the box, so a VDB cropped to its active voxels renders
  // like the dense texture it came from.
  p.sigma_t_per_m = s.sigma_t > 0 ? s.sigma_t : cloudgen::default_extinction_per_metre(min_voxel);
  p.erosion = s.erosion;
  p.density_scale = s.density;
  p.powder_c = s.powder_c;
  p.step_m = dt;
  p.large_step_count = k;
  p.max_distance_m = s.max_distance;
  // Layer rays can run to the horizon: cap the loop (use render.adaptive=true there).
  p.max_iterations = layer ? 2048.0 + 8.0 * s.steps : 4.0 * std::ceil(diag / dt) + 64.0;
  p.adaptive = s.adaptive ? 1 : 0;
  p.adaptive_start_m = s.adaptive_start > 0 ? s.adaptive_start : 0.25 * max_extent;
  p.adaptive_growth_per_m = s.adaptive_growth > 0 ? s.adaptive_growth : 4.0 / max_extent;
  const bool skipping = s.occupancy && s.skipping != Skipping::None;
  const bool distance = skipping && s.skipping == Skipping::Distance && !vol.dist.empty();
  p.occupancy_skip = skipping ? 1 : 0;
  p.skip_distance = distance ? 1 : 0;
  // The distance field's empty radius (march.glsl, empty_radius): d cells of the smallest world
  // cell edge, less the half voxel trilinear density reaches past a non-empty cell.
  p.df_cell_m = cell_m;
  p.df_margin_m = 0.5 * min_voxel;
  p.light_mode = !s.light_march ? CV_LIGHT_OFF : (skipping && s.occupancy_light ? CV_LIGHT_MARCH_SKIP_EMPTY : CV_LIGHT_MARCH);
  p.df_light = distance && s.occupancy_light ? 1 : 0;
  p.transmittance_cutoff = s.transmittance_cutoff;
  p.density_step = s.density_step;
  p.density_step_below = s.density_step_below;
  // The light volume: box mode only (layer mode's coverage map does not repeat with the texture).
  p.light_volume_on = s.light_volume && s.light_march && !layer ? 1 : 0;
  // Its grid: the voxels / scale per axis, the scale doubled until at most kMaxLightVolumeTexels
  // (16 MiB of R32F; the 128^3 thesis volume fits at scale 1), so a large field neither exhausts
  // memory nor spends minutes rebuilding on a CPU rasteriser.
  int lv_scale = s.light_volume_scale;
  auto lv_texels = [&](int sc) {
    double n = 1;
    for (int i = 0; i < 3; ++i) n *= double(std::max(1, (vol.dims[size_t(i)] + sc - 1) / sc));
    return n;
  };
  while (lv_texels(lv_scale) > double(kMaxLightVolumeTexels)) lv_scale *= 2;
  for (int i = 0; i < 3; ++i)
    p.light_volume_dims[i] = std::max(1, (vol.dims[size_t(i)] + lv_scale - 1) / lv_scale);
  p.light_samples = s.light_samples;
  p.light_step_m = s.light_step > 0 ? s.light_step : 2.5 * min_voxel;
  p.light_growth = s.light_growth;
  p.phase_mode = double(int(s.phase));
  p.hg_g = s.g;
  p.mie_table_size = double(mie_phase_table().size());
  p.powder_strength = s.powder;
  p.jitter = s.jitter ? 1 : 0;
  p.frame_index = s.frame;
  p.exact_filter = s.exact_filter ? 1 : 0;
  p.output_mode = double(int(s.output));
  double gh = ground_height(vol, s);
  f.ground_half_extent = layer ? 2e5 : 5e4;
  p.ground_y_m = gh - cam.eye.y;
  p.ground_albedo = s.ground_albedo;
  p.ground_on = s.ground ? 1 : 0;
  p.ground_half_extent_m = f.ground_half_extent;
  p.camera_world_mod_m = glm::mod(cam.eye, glm::dvec3(1024.0));
  p.shadow_samples = s.shadow_samples;
  p.sky_zenith = glm::dvec3(0.12, 0.24, 0.55);
  p.sun_disc_scale = 40.0;
  p.earth_radius_m = s.earth_radius;
  p.sky_mode = s.sky == SkyMode::Precomputed ? CV_SKY_PRECOMPUTED : CV_SKY_ANALYTIC;
  p.sky_altitude_m = cam.eye.y - gh;
  if (s.sky == SkyMode::Precomputed) {
    // The atmosphere colours the sunlight: white at the top of the atmosphere, and the ambient
    // sky light from the atmosphere's sky irradiance at the camera (sky_ambient_color).
    p.sun_color = glm::dvec3(1.0);
    p.ambient_color = sky_ambient_color(s.atmosphere, sun.direction(), s.sun_intensity, cam.eye.y - gh);
  }
  if (layer) {
    double period = size.x * s.coverage_tiles;
    p.layer_on = 1.0;
    p.layer_bottom_m = alt.x;
    p.layer_top_m = alt.y;
    p.camera_altitude_m = cam.eye.y - gh;
    p.camera_tile_x_m = glm::mod(cam.eye.x, size.x);
    p.camera_tile_z_m = glm::mod(cam.eye.z, size.z);
    p.coverage_period_m = period;
    p.tile_x_m = size.x;
    p.tile_z_m = size.z;
    p.camera_coverage_x_m = glm::mod(cam.eye.x, period);
    p.camera_coverage_z_m = glm::mod(cam.eye.z, period);
    p.coverage_bias = s.coverage;
    p.cloud_type = s.cloud_type;
  }
  f.params = rounded_to_float(p);
  f.view_proj = view_projection(cam, width, height);
  f.inv_view_proj = glm::dmat4(glm::mat4(glm::inverse(f.view_proj)));
  return f;
}

}  // namespace cloudviewer
