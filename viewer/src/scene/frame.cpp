// Parameter packing: the CloudParams block both renderers consume, from the volume, settings,
// camera and sun.
#include <algorithm>
#include <cmath>

#include "cloudgen/motion.h"
#include "cloudgen/phase.h"
#include "cloudgen/view.h"
#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

namespace {

// Whether the clouds move in this frame: a time, a motion that moves, and not a baked frame (already
// displaced).
bool clouds_move(const RenderSettings& s, bool baked) { return s.time != 0 && cloudgen::motion_moves(s.motion) && !baked; }

// Motion (cloudgen/motion.glsl): the parameters, the box the march must cover at this time and the
// large step that keeps occupancy skipping exact while the clouds are displaced.
void apply_motion(const RenderSettings& s, bool baked, double height, double moved_large_steps, ref::CloudParams& p) {
  p.march_min_m = p.volume_min_m;
  p.march_size_m = p.volume_size_m;
  p.time_s = s.time;
  const cloudgen::MotionParams& m = s.motion;
  glm::dvec2 wind = cloudgen::motion_glsl::wind_direction_xz(m.wind_direction);
  p.wind_dir_x = wind.x;
  p.wind_dir_z = wind.y;
  p.wind_speed_mps = m.wind_speed;
  p.wind_shear = m.wind_shear;
  p.flow_speed_hz = m.flow_speed;
  p.flow_up_m = m.flow_up;
  p.flow_forward_m = m.flow_forward;
  p.motion_on = clouds_move(s, baked) ? 1 : 0;
  p.motion_stretch = 1.0;
  // The curl distortion of the detail lookup (cloudgen/curl_distortion.glsl), over the box or the
  // repeating texture; a baked frame already holds it.
  const glm::dvec3 extent = p.layer_on > 0.5 ? glm::dvec3(p.tile_x_m, p.layer_top_m - p.layer_bottom_m, p.tile_z_m)
                                             : p.volume_size_m;
  p.curl_amplitude_m = baked ? 0.0 : m.curl_amplitude;
  p.curl_repeats = cloudgen::curl_repeats(m, extent);
  p.curl_shift = cloudgen::curl_shift(m, s.time, extent.y, p.curl_repeats.y);
  if (p.motion_on < 0.5) return;
  // Moving clouds: the distance field's jumps are proven for the still volume, and the light volume
  // needs a rebuild every frame; the first gives way to the moved grid's field in box mode (make_frame)
  // and, in layer mode, to the still field's jumps shortened by the stretch below (make_frame keeps
  // them on), the second to the per-sample light march unless make_frame finds the rebuild cheaper.
  p.skip_distance = 0;
  p.df_light = 0;
  p.light_volume_on = 0;  // make_frame brings it back, rebuilt per frame, where that pays
  p.ms_volume_on = 0;  // the diffusion solve is per still volume too: the octaves light moving clouds
  // D over the height fraction h in [0, 1], sampled finely: its range (the box grows by it) and its
  // steepest slope G = max |dD/dh| (metres per unit h), both padded by a quarter for what falls
  // between samples.
  const int n = 512;
  glm::dvec3 lo(0.0), hi(0.0), prev = cloudgen::motion_displacement(m, s.time, 0.0);
  double slope = 0;
  for (int i = 0; i <= n; ++i) {
    glm::dvec3 d = cloudgen::motion_displacement(m, s.time, double(i) / n);
    lo = glm::min(lo, d);
    hi = glm::max(hi, d);
    if (i > 0) slope = std::max(slope, glm::length(d - prev) * n);
    prev = d;
  }
  slope *= 1.25;
  glm::dvec3 pad(slope / n);
  if (p.tiles_xz > 0.5) {  // a tileable volume scrolls through its box (x and z wrap): the box stays
    lo.x = hi.x = lo.z = hi.z = 0.0;
    pad.x = pad.z = 0.0;
  }
  p.march_min_m = p.volume_min_m + lo - pad;
  p.march_size_m = p.volume_size_m + (hi - lo) + 2.0 * pad;
  // Occupancy skipping looks cells up at the displaced position q = p - D(h(p)). Along a large step
  // of length L, h changes by at most L / H (H: the height the volume spans), so q moves at most
  // L (1 + G / H): shorten the large step by that factor and the proof in make_frame still holds.
  double stretch = 1.0 + slope / height;
  p.motion_stretch = stretch;  // the still field's jumps (lighting.glsl empty_radius_of), same proof
  if (p.layer_on < 0.5) p.large_step_count = moved_large_steps;  // box mode: the moved grid's clearance
  p.large_step_count = std::floor(p.large_step_count / stretch);  // 0: make_frame stops the thesis scheme
  double diag = glm::length(p.march_size_m);
  if (p.layer_on < 0.5) p.max_iterations = std::max(p.max_iterations, 4.0 * std::ceil(diag / p.step_m) + 64.0);
}

// Moving clouds in box mode: the occupancy grid of the march box at this time, so that occupied()
// needs no motion lookup (medium.glsl). Cells are the volume's coarse cells in size, laid from
// march_min_m. What is seen at p is the static volume at q = p - D(h(p)), with D the motion table
// interpolated linearly (what both renderers use), so over a cell's heights D stays within the
// range of the table entries that span them: the static points a cell can show lie in its box
// moved by that range (grown by half a voxel for rounding). The cell is marked when any static cell
// there is within `reach` cells of a cell holding density (the distance field's d <= reach; the
// padded grid when a volume has no field, padding >= 1, reach 1). Unmarked, p's q is `reach`
// whole cells from density, so density is 0 at p and, along a large step of L (1 + G / H) <
// reach x cell - voxel / 2, at every point of it: apply_motion's shortened large step keeps the
// march exact as before. The moved grid's cells are `reach` static cells wide (see
// moved_reach_cells).
void build_moved_occupancy(const PreparedVolume& vol, const std::vector<glm::dvec3>& table, int reach, bool use_dist,
                           ref::CloudParams& p, std::vector<uint8_t>& out) {
  const double static_cell = vol.occ_cell * vol.voxel_size;
  const double cell = reach * static_cell;
  const glm::dvec3 origin = p.march_min_m - p.volume_min_m;  // the march box's min, volume-local metres
  glm::ivec3 n(1);
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::ceil(p.march_size_m[a] / cell - 1e-9)));
  const std::array<int, 3>& sn = vol.occ_dims;
  const double cells = double(n.x) * n.y * n.z;
  if (cells > double(1 << 24) || std::max(n.x, std::max(n.y, n.z)) > 2048) {  // absurd times: no skipping
    p.moved_occ_dims = glm::dvec3(1.0);
    p.moved_occ_cell_m = std::max(p.march_size_m.x, std::max(p.march_size_m.y, p.march_size_m.z)) + 1.0;
    out.assign(1, 1);
    return;
  }
  p.moved_occ_dims = glm::dvec3(n);
  p.moved_occ_cell_m = cell;
  const double margin = 0.5 * vol.voxel_size;
  const int last = CV_MOTION_LUT_SIZE - 1;
  auto h_of = [&](double y_local) { return (vol.origin.y + y_local - vol.height_min) / vol.height_size; };
  // A static axis range [lo, hi] (metres) as cell indices; false when it misses a non-wrapping volume.
  auto span = [&](double lo, double hi, int axis, bool wraps, int& i0, int& i1) {
    i0 = int(std::floor(lo / static_cell));
    i1 = int(std::floor(hi / static_cell));
    if (wraps) {
      if (i1 - i0 >= sn[axis]) i0 = 0, i1 = sn[axis] - 1;
      return true;
    }
    i0 = std::max(i0, 0);
    i1 = std::min(i1, sn[axis] - 1);
    return i0 <= i1;
  };
  // Per static y layer, a summed-area table over (x, z) of the cells near density (built with the
  // grid, PreparedVolume::moved_near_sat): a moved cell's footprint, which long times and strong
  // shear stretch over the whole tile, then costs its y span times at most four look-ups, not its
  // cells.
  const int sx = sn[0], sy = sn[1], sz = sn[2];
  std::vector<uint32_t> local;
  const size_t sat_size = size_t(sy) * (sz + 1) * (sx + 1);
  if (!use_dist || reach != moved_reach_cells(vol) || vol.moved_near_sat.size() != sat_size)
    local = moved_near_table(vol, reach, use_dist);
  const std::vector<uint32_t>& sat = local.empty() ? vol.moved_near_sat : local;
  auto at = [&](int y, int z, int x) { return sat[(size_t(y) * (sz + 1) + z) * (sx + 1) + x]; };
  // A span from span() as at most two ranges inside [0, n) (a wrapping axis may run past an end).
  auto pieces = [](int i0, int i1, int len, std::array<std::array<int, 2>, 2>& r) {
    const int a = ((i0 % len) + len) % len, b = a + (i1 - i0);
    if (b < len) {
      r[0] = {a, b};
      return 1;
    }
    r[0] = {a, len - 1}, r[1] = {0, b - len};
    return 2;
  };
  glm::dvec3 dlo(0.0), dhi(0.0);  // the displacement range over the heights of the row at hand
  // Cell c of the moved grid along horizontal axis a as at most two ranges of static cells (0: none).
  auto ranges = [&](int a, int c, std::array<std::array<int, 2>, 2>& r) {
    const double lo = origin[a] + c * cell - margin, hi = origin[a] + (c + 1) * cell + margin;
    int i0, i1;
    if (!span(lo - dhi[a], hi - dlo[a], a, vol.tiles, i0, i1)) return 0;
    return pieces(i0, i1, sn[size_t(a)], r);
  };
  out.assign(size_t(cells), 0);
  for (int j = 0; j < n.y; ++j) {
    double y0 = origin.y + j * cell - margin, y1 = origin.y + (j + 1) * cell + margin;
    double h0 = std::clamp(h_of(y0), 0.0, 1.0) * last, h1 = std::clamp(h_of(y1), 0.0, 1.0) * last;
    int e0 = std::clamp(int(std::floor(h0)), 0, last), e1 = std::clamp(int(std::ceil(h1)), 0, last);
    dlo = dhi = table[size_t(e0)];
    for (int e = e0; e <= e1; ++e) dlo = glm::min(dlo, table[size_t(e)]), dhi = glm::max(dhi, table[size_t(e)]);
    int y_0, y_1;
    if (!span(y0 - dhi.y, y1 - dlo.y, 1, false, y_0, y_1)) continue;
    for (int k = 0; k < n.z; ++k) {
      std::array<std::array<int, 2>, 2> zr, xr;
      const int nzr = ranges(2, k, zr);
      for (int i = 0; i < n.x && nzr > 0; ++i) {
        const int nxr = ranges(0, i, xr);
        bool hit = false;
        for (int y = y_0; y <= y_1 && !hit; ++y)
          for (int a = 0; a < nzr && !hit; ++a)
            for (int b = 0; b < nxr && !hit; ++b) {
              const int za = zr[size_t(a)][0], zb = zr[size_t(a)][1], xa = xr[size_t(b)][0], xb = xr[size_t(b)][1];
              hit = at(y, zb + 1, xb + 1) + at(y, za, xa) - at(y, za, xb + 1) - at(y, zb + 1, xa) > 0;
            }
        out[(size_t(k) * n.y + j) * n.x + i] = hit ? 1 : 0;
      }
    }
  }
}

// render.shadow_map (box mode): the ground texels whose sun rays cross the march box. A ground
// point g (box-relative) reaches height y at g.xz + s.xz (y - g.y) / s.y, so its ray meets the box
// only if that lies in [0, W] for some y of the box above the ground: g.xz within [-max d, W -
// min d], d(y) = s.xz (y - g.y) / s.y taken at the ends of that height range. Texels are
// shadow_map_scale voxels wide, doubled until each side has at most kMaxShadowMapSide. Moving
// clouds rebuild the map every frame, which pays only while it has fewer texels than the frame
// has ground pixels to march: with more than a quarter of the frame's pixels, they march.
void set_shadow_map(const RenderSettings& s, int width, int height, ref::CloudParams& p) {
  p.shadow_map_on = 0;
  const glm::dvec3 sun = p.sun_dir;
  // The ground's height in the march box, to 1 mm so a camera move (camera-relative positions)
  // does not change the map's geometry or key by a rounding.
  const double gy = std::round((p.ground_y_m - p.march_min_m.y) * 1000.0) / 1000.0;
  p.shadow_map_ground_m = gy;
  const double y0 = std::max(0.0, gy), y1 = p.march_size_m.y;
  if (!s.shadow_map || p.layer_on > 0.5 || p.ground_on < 0.5 || sun.y <= 1e-6 || !(y1 > y0)) return;
  const glm::dvec2 sxz(sun.x / sun.y, sun.z / sun.y);
  const glm::dvec2 d0 = sxz * (y0 - gy), d1 = sxz * (y1 - gy);
  const glm::dvec2 lo = -glm::max(d0, d1), hi = glm::dvec2(p.march_size_m.x, p.march_size_m.z) - glm::min(d0, d1);
  double texel = p.voxel_size_m * s.shadow_map_scale;
  auto side = [&](double extent) { return std::max(1.0, std::ceil(extent / texel)); };
  while (side(hi.x - lo.x) > kMaxShadowMapSide || side(hi.y - lo.y) > kMaxShadowMapSide) texel *= 2;
  if (p.motion_on > 0.5 && side(hi.x - lo.x) * side(hi.y - lo.y) * 4.0 > double(width) * double(height)) return;
  p.shadow_map_on = 1;
  p.shadow_map_texel_m = texel;
  p.shadow_map_nx = side(hi.x - lo.x);
  p.shadow_map_nz = side(hi.y - lo.y);
  p.shadow_map_min_x_m = lo.x;
  p.shadow_map_min_z_m = lo.y;
}

}  // namespace

std::vector<glm::dvec3> motion_table_row(const RenderSettings& s, double t) {
  std::vector<glm::dvec3> row(CV_MOTION_LUT_SIZE);
  for (int i = 0; i < CV_MOTION_LUT_SIZE; ++i)
    row[size_t(i)] = cloudgen::motion_displacement(s.motion, t, double(i) / (CV_MOTION_LUT_SIZE - 1));
  return row;
}


void set_phase_params(ref::CloudParams& p, const RenderSettings& s) {
  p.phase_mode = double(int(s.phase));
  p.hg_g = s.g;
  p.hg_g2 = s.g2;
  p.lobe_weight = s.lobe_weight;
  // The HG + Draine fit's parameters (cloudgen/phase_lobes.glsl, through cloudgen::phase).
  const cloudgen::phase::DraineHgFit fit = cloudgen::phase::draine_hg_fit(s.droplet_diameter);
  p.draine_g_hg = fit.g_hg, p.draine_g_d = fit.g_d, p.draine_alpha = fit.alpha, p.draine_w_d = fit.w_d;
}

FieldRule field_rule(const PreparedVolume& vol, const RenderSettings& s) {
  FieldRule r;
  const double curl = vol.baked_motion ? 0.0 : s.motion.curl_amplitude;  // as apply_motion
  if (!s.eroded_field || !vol.has_detail || !(s.erosion > 0) || curl != 0 || vol.nano) return r;
  r.erosion = s.erosion;
  r.layer = s.mode == PlaceMode::Layer;
  if (clouds_move(s, vol.baked_motion)) {
    // motion.glsl: the up displacement is h (offset(t) - offset(0)) flow_up with h <= 1 and each
    // offset in [-1, 1] (a flow map image too), so the seen height moves at most 2 |flow_up| / H.
    glm::dvec2 alt = r.layer ? layer_altitudes(vol, s) : glm::dvec2(0.0, vol.height_size);
    r.height_slack = 2.0 * std::abs(s.motion.flow_up) / std::max(alt.y - alt.x, 1e-9);
  }
  return r;
}

bool fit_distance_field(PreparedVolume& vol, const RenderSettings& s) {
  if (vol.dist.empty()) return false;
  const FieldRule need = field_rule(vol, s);
  // Rebuilt when it does not serve the frame, or when the frame erodes and the field does not yet:
  // a frame that erodes more than the field assumed, or moves less, keeps it (still exact).
  const bool base_only = !(vol.dist_rule.erosion > 0);
  if (field_covers(vol.dist_rule, need) && !(base_only && need.erosion > 0)) return false;
  build_distance_field(vol, need);
  return true;
}

namespace {

/// The march's geometry for a volume and settings: the placed size, the small step, the thesis
/// scheme's large step and what the distance field may prove.
struct MarchGeometry {
  bool layer = false;
  glm::dvec3 size{0.0};  ///< world size of the box (layer: the texture stretched over the layer)
  glm::dvec2 alt{0.0};   ///< layer bottom and top altitudes (layer mode)
  double min_voxel = 0, max_extent = 0, diag = 0;
  double dt = 0;         ///< the small step
  double cell_m = 0;     ///< a coarse cell's edge in the smallest world voxel edge
  int large_steps = 0;   ///< the thesis scheme's large step in small steps (0: see make_frame)
  bool field_ok = false; ///< the distance field serves this frame (field_covers)
  int reach = 1;         ///< moved-grid cells per still cell (moved_reach_cells)
  int moved_large_steps = 0;
};

MarchGeometry march_geometry(const PreparedVolume& vol, const RenderSettings& s) {
  MarchGeometry g;
  g.layer = s.mode == PlaceMode::Layer;
  if (g.layer && !vol.tiles)
    throw InputError("render.mode=layer repeats the texture over the sky, so it needs a tileable volume "
                     "(x and z wrap; cloudgen presets and synthetic:noise tile, this input does not)");
  g.size = vol.size();
  if (g.layer) {
    g.alt = layer_altitudes(vol, s);
    g.size.y = g.alt.y - g.alt.x;  // the texture's height stretches over the layer
  }
  const glm::dvec3 voxel = g.size / glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2]);
  g.min_voxel = std::min(voxel.x, std::min(voxel.y, voxel.z));
  g.max_extent = std::max(g.size.x, std::max(g.size.y, g.size.z));
  g.diag = glm::length(g.size);
  g.dt = g.max_extent / s.steps;
  g.cell_m = vol.occ_cell * g.min_voxel;
  // Large step: k small steps, just under the padding's clearance less half a voxel. Why that is
  // safe: the grid is the cells holding density dilated by P = occ_padding cells per axis (a box
  // dilation, wrapped where the volume tiles), so from a point of an unoccupied cell every cell
  // within P cells along each axis holds no density, and any point less than P cells away in each
  // axis lies in one of them. Non-zero density (trilinear reaches half a voxel past a non-empty
  // cell) is thus at least P x cell - voxel/2 away along every axis, and a segment shorter than
  // that from an unoccupied start cannot touch it. Where a tiling axis ends in a partial cell of
  // w < cell voxels, P cells across the wrap may span only (P - 1) x cell + w voxels: the clearance
  // takes the narrowest. (The thesis's own step is one cell on its double padding; the second cell
  // of padding is clearance the step now uses, 2x longer at the default padding 2.)
  // In layer mode cells are measured in the smallest world voxel edge (the texture may be stretched
  // vertically); the Earth's curvature bends a large step by d^2/2R, far below half a voxel.
  double clearance_voxels = vol.occ_padding * vol.occ_cell;
  if (vol.tiles || g.layer)
    for (int a : {0, 2}) {
      const int w = vol.dims[size_t(a)] % vol.occ_cell;  // the partial cell at the seam, if any
      if (w != 0) clearance_voxels = std::min(clearance_voxels, double((vol.occ_padding - 1) * vol.occ_cell + w));
    }
  g.large_steps = int(std::floor(0.999 * (clearance_voxels - 0.5) * g.min_voxel / g.dt));  // 0: see make_frame
  // The distance field serves this frame only if it was built for an erosion and motion no
  // stronger than the frame's (field_covers); otherwise the thesis scheme on the padded grid.
  g.field_ok = !vol.dist.empty() && field_covers(vol.dist_rule, field_rule(vol, s));
  g.reach = g.layer || !g.field_ok ? 1 : moved_reach_cells(vol);
  const double moved_clearance = g.reach * g.cell_m - 0.5 * g.min_voxel;  // from a point of an unmarked moved cell
  g.moved_large_steps = int(std::floor(0.999 * moved_clearance / g.dt));
  return g;
}

/// The volume's placement and the medium: where the box is, its grids, the sun and the extinction.
void set_volume_params(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam, const Sun& sun,
                       const MarchGeometry& g, ref::CloudParams& p) {
  p.volume_min_m = vol.origin - cam.eye;
  p.voxel_size_m = vol.voxel_size;
  p.volume_size_m = g.size;  // box mode only
  p.tiles_xz = vol.tiles || g.layer ? 1.0 : 0.0;
  p.volume_dims = glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2]);
  p.has_detail = vol.has_detail ? 1.0 : 0.0;
  p.occ_dims = glm::dvec3(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  p.occ_cell_voxels = vol.occ_cell;
  p.sun_dir = sun.direction();
  p.sun_radiance = s.sun_intensity;
  p.sun_color = glm::dvec3(1.0, 0.96, 0.9);
  p.ambient_scale = s.ambient;
  p.ambient_color = glm::dvec3(0.30, 0.38, 0.52);
  p.ambient_below_color = p.ambient_color;  // the analytic sky: one constant ambient
  p.albedo = s.albedo;
  // Auto values follow the voxel size, not the box, so a VDB cropped to its active voxels renders
  // like the dense texture it came from.
  p.sigma_t_per_m = s.sigma_t > 0 ? s.sigma_t : cloudgen::default_extinction_per_metre(g.min_voxel);
  p.erosion = s.erosion;
  p.density_scale = s.density;
  p.powder_c = s.powder_c;
}

/// The primary march: steps, their growth and empty-space skipping. Returns whether the frame
/// skips by a distance (the field's or the NanoVDB tree's).
bool set_march_params(const PreparedVolume& vol, const RenderSettings& s, const MarchGeometry& g,
                      ref::CloudParams& p) {
  p.step_m = g.dt;
  p.large_step_count = g.large_steps;
  p.max_distance_m = s.max_distance;
  // Layer rays can run to the horizon: cap the loop (use render.adaptive=true there).
  p.max_iterations = g.layer ? 2048.0 + 8.0 * s.steps : 4.0 * std::ceil(g.diag / g.dt) + 64.0;
  p.adaptive = s.adaptive ? 1 : 0;
  p.adaptive_start_m = s.adaptive_start > 0 ? s.adaptive_start : 0.25 * g.max_extent;
  p.adaptive_growth_per_m = s.adaptive_growth > 0 ? s.adaptive_growth : 4.0 / g.max_extent;
  const bool skipping = s.occupancy && s.skipping != Skipping::None;
  // Tree skipping proves its jumps from the NanoVDB tree (lighting.glsl tree_radius_seen): the
  // distance skipping's paths with another radius, and no field to fit.
  const bool tree = skipping && s.skipping == Skipping::Tree;
  if (tree && !vol.nano)
    throw InputError("render.skipping=tree jumps through the NanoVDB tree's empty nodes, so it needs "
                     "render.volume=nanovdb (this volume is on the dense path; or use render.skipping=distance)");
  const bool distance = skipping && ((s.skipping == Skipping::Distance && g.field_ok) || tree);
  p.occupancy_skip = skipping ? 1 : 0;
  p.skip_distance = distance ? 1 : 0;
  p.skip_tree = tree ? 1 : 0;
  // The distance field's empty radius (march.glsl, empty_radius): d cells of the smallest world
  // cell edge, less the half voxel trilinear density reaches past a non-empty cell.
  p.df_cell_m = g.cell_m;
  p.df_margin_m = 0.5 * g.min_voxel;
  p.light_mode = !s.light_march ? CV_LIGHT_OFF : (skipping && s.occupancy_light ? CV_LIGHT_MARCH_SKIP_EMPTY : CV_LIGHT_MARCH);
  p.df_light = distance && s.occupancy_light ? 1 : 0;
  p.transmittance_cutoff = s.transmittance_cutoff;
  p.density_step = s.density_step;
  p.density_step_below = s.density_step_below;
  return distance;
}

/// The lighting: the light volume's and the diffusion volume's grids, the light march, the phase
/// function and the multiple-scattering octaves.
void set_light_params(const PreparedVolume& vol, const RenderSettings& s, const MarchGeometry& g,
                      ref::CloudParams& p) {
  // The light volume: box mode only (layer mode's coverage map does not repeat with the texture).
  p.light_volume_on = s.light_volume && s.light_march && !g.layer ? 1 : 0;
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
  // The diffusion volume (box mode too): its cells the same way, at most kMaxMsVolumeCells.
  p.ms_volume_on = s.ms_volume && !g.layer ? 1 : 0;
  int ms_scale = s.ms_volume_scale;
  while (lv_texels(ms_scale) > double(kMaxMsVolumeCells)) ms_scale *= 2;
  for (int i = 0; i < 3; ++i) p.ms_volume_dims[i] = std::max(1, (vol.dims[size_t(i)] + ms_scale - 1) / ms_scale);
  p.light_samples = s.light_samples;
  p.light_step_m = s.light_step > 0 ? s.light_step : 2.5 * g.min_voxel;
  p.light_growth = s.light_growth;
  set_phase_params(p, s);
  p.mie_table_size = CV_MIE_TABLE_SIZE;  // the table itself is computed only for Mie frames
  p.powder_strength = s.powder;
  p.ms_octaves = s.ms_octaves;
  p.ms_attenuation = s.ms_attenuation;
  p.ms_extinction = s.ms_extinction;
  p.ms_eccentricity = s.ms_eccentricity;
  p.jitter = s.jitter ? 1 : 0;
  p.frame_index = s.frame;
  p.exact_filter = s.exact_filter ? 1 : 0;
  p.output_mode = double(int(s.output));
}

/// The ground, the sky and the sunlight's colour (the precomputed atmosphere's when it is on).
void set_ground_and_sky(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam, const Sun& sun,
                        const MarchGeometry& g, FrameSetup& f) {
  ref::CloudParams& p = f.params;
  const double gh = ground_height(vol, s);
  f.ground_half_extent = g.layer ? 2e5 : 5e4;
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
  p.sky_lut = s.sky == SkyMode::Precomputed && s.sky_lut ? 1 : 0;
  // render.air_lut from inside the air only: from above it, the limb's thin glow (a degree or two
  // seen from 1000 km) falls between the table's rows (PSNR 38 dB against the march), so the sky
  // is marched there.
  const bool inside_air = s.atmosphere.bottom_radius + (cam.eye.y - gh) < s.atmosphere.top_radius;
  p.air_lut = s.sky == SkyMode::Precomputed && s.air_lut && inside_air ? 1 : 0;
  if (s.sky == SkyMode::Precomputed) {
    // The atmosphere colours the sunlight: white at the top of the atmosphere, and the ambient
    // sky light from the atmosphere's irradiance at the camera from above and from below (sky_ambient).
    p.sun_color = glm::dvec3(1.0);
    SkyAmbient a = sky_ambient(s.atmosphere, sun.direction(), s.sun_intensity, cam.eye.y - gh);
    p.ambient_color = a.above;
    p.ambient_below_color = a.below;
  }
  if (g.layer) {
    double period = g.size.x * s.coverage_tiles;
    p.layer_on = 1.0;
    p.layer_bottom_m = g.alt.x;
    p.layer_top_m = g.alt.y;
    p.camera_altitude_m = cam.eye.y - gh;
    p.camera_tile_x_m = glm::mod(cam.eye.x, g.size.x);
    p.camera_tile_z_m = glm::mod(cam.eye.z, g.size.z);
    p.coverage_period_m = period;
    p.tile_x_m = g.size.x;
    p.tile_z_m = g.size.z;
    p.camera_coverage_x_m = glm::mod(cam.eye.x, period);
    p.camera_coverage_z_m = glm::mod(cam.eye.z, period);
    p.coverage_bias = s.coverage;
    p.cloud_type = s.cloud_type;
  }
  p.height_min_m = vol.height_min - cam.eye.y;
  p.height_size_m = vol.height_size;
}

/// Moving clouds: the motion table, the skipping they allow, the moved occupancy grid and the
/// light volume over the march box. Also the large step's floor, which holds still or moving.
void set_motion(const PreparedVolume& vol, const RenderSettings& s, const MarchGeometry& g, bool distance,
                int width, int height, FrameSetup& f) {
  ref::CloudParams& p = f.params;
  apply_motion(s, vol.baked_motion, g.layer ? g.size.y : vol.height_size, g.moved_large_steps, p);
  if (p.motion_on > 0.5) {
    f.motion_table = motion_table_row(s, s.time);
    f.motion_table.insert(f.motion_table.end(), f.motion_table.begin(), f.motion_table.end());
    // Distance skipping while the clouds move, box and layer mode alike: the still field, read at
    // the static point seen (as the density is), proves no density within r of that point; along
    // a jump of J the static point moves at most J x stretch (apply_motion), so jumps of
    // r / stretch stay exact (lighting.glsl empty_radius_of). The field must cover the motion's up
    // flow (field_covers: fit_distance_field builds it so).
    if (distance) p.skip_distance = 1;
  }
  // A clearance shorter than one small step (cells of a voxel or two, a thin partial cell at the
  // seam, few steps, steep motion) proves nothing about the sample a large step of one small step
  // skips: the thesis scheme then samples every step. Distance skipping proves its own jumps and
  // reads the count only as its re-check interval.
  if (p.large_step_count < 1.0) {
    if (p.skip_distance < 0.5) p.occupancy_skip = 0;
    p.large_step_count = 1.0;
  }
  if (p.skip_distance < 0.5) p.skip_tree = 0;  // no jumps at all: no tree to read
  // The moved grid serves occupied() alone: the thesis scheme's march and the light march that skips
  // empty cells (render.occupancy_light; apply_motion turns its field off). A frame that reads
  // neither, as with the defaults' distance skipping, does not build it (6.6 ms a frame on
  // cumulus-field 1024, bench/bench_frame); both renderers then treat every moved cell as occupied
  // (GL binds the still grid, which no call reads).
  const bool reads_occupied = (p.occupancy_skip > 0.5 && p.skip_distance < 0.5) ||
                              (int(p.light_mode) == CV_LIGHT_MARCH_SKIP_EMPTY && p.df_light < 0.5);
  if (p.motion_on > 0.5 && !g.layer && reads_occupied)
    build_moved_occupancy(vol, f.motion_table, g.reach, g.field_ok, p, f.moved_occupancy);
  // Moving clouds (box mode): the light volume over the march box from this frame's moving
  // density, rebuilt every frame (lighting.glsl light_volume_position), with the still grid's
  // texel. A rebuild marches toward the sun from every texel, the per-sample march from every
  // cloud sample of every pixel, so it pays when the grid has no more texels than the frame
  // marches pixels (then one cloud sample per pixel already costs as much); smaller frames, and
  // larger grids, march per sample as before. Temporal upsampling marches one pixel in 16.
  if (p.motion_on > 0.5 && !g.layer && s.light_volume && s.light_march) {
    const double marched = double(width) * double(height) / (s.temporal ? 16.0 : 1.0);
    const glm::dvec3 texel = p.volume_size_m / p.light_volume_dims;
    glm::dvec3 dims(1.0);
    for (int i = 0; i < 3; ++i) dims[i] = std::max(1.0, std::ceil(p.march_size_m[i] / texel[i] - 1e-6));
    const double texels = dims.x * dims.y * dims.z;
    if (texels <= marched && texels <= double(kMaxLightVolumeTexels)) {
      p.light_volume_on = 1;
      p.light_volume_dims = dims;
    }
  }
}

// Render-time detail (render.detail; medium.glsl fine_detail_threshold): the texture laid over the
// box, or the repeating texture in layer mode, a whole number of tiles per axis (so a tiling volume
// stays seamless) as near render.detail_period metres each as that allows. Strength 0 is off.
void set_fine_detail(const RenderSettings& s, ref::CloudParams& p) {
  const glm::dvec3 extent = p.layer_on > 0.5 ? glm::dvec3(p.tile_x_m, p.layer_top_m - p.layer_bottom_m, p.tile_z_m)
                                             : p.volume_size_m;
  p.fine_detail_strength = s.detail ? s.detail_strength : 0.0;
  p.fine_detail_size = s.detail_size;
  for (int i = 0; i < 3; ++i) p.fine_detail_repeats[i] = std::max(1.0, std::round(extent[i] / s.detail_period));
}

}  // namespace

FrameSetup make_frame(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam,
                      const Sun& sun, int width, int height) {
  FrameSetup f;
  f.width = width;
  f.height = height;
  f.camera = cam;
  f.sun = sun;
  f.settings = s;
  const MarchGeometry g = march_geometry(vol, s);
  ref::CloudParams& p = f.params;
  p = ref::CloudParams{};  // zero: layer fields stay 0 in box mode
  set_volume_params(vol, s, cam, sun, g, p);
  const bool distance = set_march_params(vol, s, g, p);
  set_light_params(vol, s, g, p);
  set_ground_and_sky(vol, s, cam, sun, g, f);
  set_motion(vol, s, g, distance, width, height, f);
  set_fine_detail(s, p);
  set_shadow_map(s, width, height, p);
  if (int(p.phase_mode) == CV_PHASE_MIE) f.mie = mie_table_of(s);
  if (g.layer) f.coverage = procedural_coverage_map();
  f.params = rounded_to_float(p);
  f.view_proj = view_projection(cam, width, height);
  f.inv_view_proj = glm::dmat4(glm::mat4(glm::inverse(f.view_proj)));
  return f;
}

FrameSetup make_frame_or_keep(const PreparedVolume& vol, RenderSettings& s, RenderSettings& good, const Camera& cam,
                              const Sun& sun, int width, int height, std::string& refused) {
  refused.clear();
  try {
    FrameSetup f = make_frame(vol, s, cam, sun, width, height);
    good = s;
    return f;
  } catch (const InputError& e) {
    refused = e.what();
    const double time = s.time;
    const int frame = s.frame;
    s = good;
    s.time = time;
    s.frame = frame;
    return make_frame(vol, s, cam, sun, width, height);
  }
}

}  // namespace cloudviewer
