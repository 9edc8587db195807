// The participating medium: the volume's density at a point, box or layer placement, and the
// coarse occupancy grid. A. Schneider, "The Real-Time Volumetric Cloudscapes of Horizon Zero Dawn",
// SIGGRAPH 2015 (seed 001): base shape R eroded by the G/B/A detail fBm with a remap; in layer mode
// the tileable texture repeats over a cloud layer between two altitudes over a curved Earth, a 2D
// coverage map says where clouds are and the cloud-type height gradient (cloudgen's
// cloud_type.glsl, shared with cloudgen) shapes their profile.
// Needs common.glsl, cloud_type.glsl, erosion.glsl, `u_cloud` and the lookups volume_texel, volume_filtered,
// occupancy_texel, coverage_texel, coverage_size, fine_detail_texel and fine_detail_filtered (see march.glsl).

// Trilinear filter done by hand from texel fetches: texel centres at (i + 0.5) / n, x and z
// wrapped for tileable volumes, clamped otherwise (GL_REPEAT / GL_CLAMP_TO_EDGE semantics).
vec4 volume_trilinear(vec3 uvw) {
  ivec3 n = ivec3(u_cloud.volume_dims);
  bool tiles = CV_MODE_TILES > 0.5;
  TrilinearCell cell = trilinear_cell(uvw, n);
  ivec3 i0 = cell.i0;
  vec3 f = cell.f;
  vec4 acc = vec4(0.0);
  for (int k = 0; k < 8; ++k) acc += trilinear_weight(f, k) * volume_texel(trilinear_corner(i0, k, n, tiles));
  return acc;
}

bool layer_mode() { return CV_MODE_LAYER > 0.5; }

// Altitude above the ground sphere of camera-relative p. Parabolic Earth: the exact
// sqrt(r^2 + (R + h)^2) - R loses everything to float rounding at R = 6360 km, while
// h + y + (x^2 + z^2) / 2R is exact to d^4/(8 R^3) (2 m at 200 km) and well conditioned.
Number layer_altitude(vec3 p) {
  return u_cloud.camera_altitude_m + p.y + (p.x * p.x + p.z * p.z) / (2.0 * u_cloud.earth_radius_m);
}

// The part [t0, t1] of the ray p + t d (t >= 0) inside the cloud layer, up to the first time it
// leaves (empty when x >= y). Altitude along the ray is the convex parabola a0 + a1 t + a2 t^2.
vec2 shell_interval(vec3 p, vec3 d) {
  Number R = u_cloud.earth_radius_m;
  Number bottom = u_cloud.layer_bottom_m;
  Number top = u_cloud.layer_top_m;
  Number a0 = layer_altitude(p);
  Number a1 = d.y + (p.x * d.x + p.z * d.z) / R;
  Number a2 = (d.x * d.x + d.z * d.z) / (2.0 * R);
  vec2 up = parabola_roots(a2, a1, a0 - top);
  vec2 down = parabola_roots(a2, a1, a0 - bottom);
  bool hits_bottom = down.x <= down.y;
  if (a0 < bottom) {  // below the layer: enter through its bottom, leave through its top
    if (!hits_bottom) return vec2(1e30, -1e30);
    return vec2(down.y, up.y);
  }
  if (a0 <= top) {  // inside: leave through the top, or the bottom when looking down
    Number t1 = up.y;
    if (hits_bottom && down.x > 0.0) t1 = min(t1, down.x);
    return vec2(0.0, t1);
  }
  if (!(up.x <= up.y) || up.y < 0.0) return vec2(1e30, -1e30);  // above, never reaching down
  Number t0 = max(up.x, 0.0);
  Number t1 = up.y;
  if (hits_bottom && down.x > t0) t1 = min(t1, down.x);
  return vec2(t0, t1);
}

// Coverage (x) and cloud type (y) at camera-relative p: bilinear, wrapped (the map tiles).
vec2 coverage_at(vec3 p) {
  ivec2 n = coverage_size();
  Number period = u_cloud.coverage_period_m;
  vec2 x = vec2((u_cloud.camera_coverage_x_m + p.x) / period * Number(n.x) - 0.5,
                (u_cloud.camera_coverage_z_m + p.z) / period * Number(n.y) - 0.5);
  vec2 fl = floor(x);
  vec2 f = x - fl;
  ivec2 i0 = ivec2(fl);
  vec2 acc = vec2(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 i = ivec2(wrap_index(i0.x + o.x, n.x), wrap_index(i0.y + o.y, n.y));
    vec2 w = mix(vec2(1.0) - f, f, vec2(o));
    acc += (w.x * w.y) * coverage_texel(i);
  }
  return acc;
}

// Normalised volume coordinates of a camera-relative position: the box, or in layer mode the
// repeating tile horizontally and the layer's height vertically.
vec3 volume_uvw(vec3 p) {
  if (layer_mode()) {
    Number h = (layer_altitude(p) - u_cloud.layer_bottom_m) / (u_cloud.layer_top_m - u_cloud.layer_bottom_m);
    return vec3((u_cloud.camera_tile_x_m + p.x) / u_cloud.tile_x_m, h,
                (u_cloud.camera_tile_z_m + p.z) / u_cloud.tile_z_m);
  }
  return (p - u_cloud.volume_min_m) / u_cloud.volume_size_m;
}

// The metres one unit of volume_uvw spans along each axis.
vec3 volume_uvw_extent_m() {
  if (layer_mode()) return vec3(u_cloud.tile_x_m, u_cloud.layer_top_m - u_cloud.layer_bottom_m, u_cloud.tile_z_m);
  return u_cloud.volume_size_m;
}

// Motion (cloudgen/motion.glsl, seed 003): the displacement D of the clouds seen at p, from p's
// height fraction in the layer (or box). Within a frame D depends on the height alone, so the
// renderer evaluates motion_displacement at CV_MOTION_LUT_SIZE heights (in C++, from the same
// text; src/frame.cpp motion_table_row) and every lookup interpolates that table linearly: two
// texel reads instead of six cosines per density sample (interpolation error under 1 cm with the
// default flow; tests/test_motion.cpp). Row 0 is this frame's time, row 1 the previous frame's (temporal reprojection).
vec3 motion_table_value(Number h, int row) {
  Number x = clamp(h, 0.0, 1.0) * Number(CV_MOTION_LUT_SIZE - 1);
  int i = min(int(floor(x)), CV_MOTION_LUT_SIZE - 2);
  Number f = x - Number(i);
  return mix(motion_texel(i, row), motion_texel(i + 1, row), f);
}
// Height fraction of camera-relative p: in the layer, or in box mode in the box heights are
// measured in (the whole preset's when the file records it: a cropped VDB erodes and moves like
// the dense volume it came from).
Number height_fraction(vec3 p) {
  if (layer_mode()) return volume_uvw(p).y;
  return (p.y - u_cloud.height_min_m) / u_cloud.height_size_m;
}
vec3 motion_at(vec3 p) {
  if (CV_MODE_MOTION < 0.5) return vec3(0.0);
  return motion_table_value(height_fraction(p), 0);
}
vec3 motion_at_previous(vec3 p) {
  if (CV_MODE_MOTION < 0.5) return vec3(0.0);
  return motion_table_value(height_fraction(p), 1);
}

// Volume coordinates of the static volume seen at p: volume_uvw(p - D). Shifted in uvw rather than
// recomputed at p - D so that a horizontal displacement never moves the layer altitude (the
// parabolic Earth term of layer_altitude depends on the horizontal distance).
vec3 moving_uvw(vec3 p, vec3 motion) { return volume_uvw(p) - motion / volume_uvw_extent_m(); }

// Render-time detail (render.detail; Schneider 2015/2017, Nubis's separate high-frequency detail
// texture): a tileable Worley fBm of fine_detail_size^3 texels (detail_texture.h) at q in its tiles,
// trilinear and wrapped on every axis, by hand (exact_filter, the CPU reference) or by the texture unit.
Number fine_detail_trilinear(vec3 q) {
  int n = int(u_cloud.fine_detail_size);
  TrilinearCell cell = trilinear_cell(q, ivec3(n));
  Number acc = 0.0;
  for (int k = 0; k < 8; ++k) {
    ivec3 i = cell.i0 + ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    acc += trilinear_weight(cell.f, k) * fine_detail_texel(ivec3(wrap_index(i.x, n), wrap_index(i.y, n), wrap_index(i.z, n)));
  }
  return acc;
}
// Its erosion threshold at static volume coordinates uvw seen at height fraction seen_h: the
// texture laid fine_detail_repeats times over the volume (or the repeating texture) per axis, at
// strength fine_detail_strength, through erosion_threshold's height rule (cloudgen/erosion.glsl:
// inverted, so wispy, near the base; billowy above). The density then takes eroded_base, the same
// remap as the volume's own detail: density' = clamp((density - e) / (1 - e), 0, 1) with
// e = strength * mix(1 - d, d, clamp(5 h, 0, 1)), d the detail in [0, 1]. It never raises density
// and keeps 0 at 0, so the occupancy grid and the distance field (built without it) stay exact bounds.
Number fine_detail_threshold(vec3 uvw, Number seen_h) {
  vec3 q = uvw * u_cloud.fine_detail_repeats;
  Number d = CV_MODE_EXACT_FILTER > 0.5 ? fine_detail_trilinear(q) : fine_detail_filtered(q);
  return erosion_threshold(d, seen_h, u_cloud.fine_detail_strength);
}

// Cloud density (dimensionless, >= 0) at camera-relative position p (moved by the motion): base shape R, eroded by the
// G/B/A detail fBm (HZD remap), scaled by the density multiplier. Zero outside the box (x and z
// repeat for tileable volumes). Erosion only lowers density, so the occupancy grid built from R
// stays conservative.
// `motion` and `uvw`: motion_at(p) and moving_uvw(p, motion), which the primary march also needs
// for its distance-field read at the same point (cloud_density finds them itself).
Number cloud_density_seen(vec3 p, vec3 motion, vec3 uvw) {
  Number seen_h = height_fraction(p);  // the height where the sample is seen (an altitude rule below)
  if (uvw.y < 0.0 || uvw.y > 1.0) return 0.0;
  bool tiles = CV_MODE_TILES > 0.5;
  if (!tiles && (uvw.x < 0.0 || uvw.x > 1.0 || uvw.z < 0.0 || uvw.z > 1.0)) return 0.0;
  vec4 v = CV_MODE_EXACT_FILTER > 0.5 ? volume_trilinear(uvw) : volume_filtered(uvw);
  Number base = v.x;
  if (layer_mode()) {
    // Coverage remap (HZD): raise the threshold where coverage is low, then scale by coverage.
    // Like erosion it only lowers density, so the texture's occupancy grid stays conservative.
    vec2 cov = coverage_at(p - motion);  // the weather map travels with the clouds
    Number c = clamp(cov.x + u_cloud.coverage_bias, 0.0, 1.0);
    Number type = u_cloud.cloud_type >= 0.0 ? u_cloud.cloud_type : cov.y;
    Number x = base * cloud_type_gradient(uvw.y, type);
    base = clamp((x - (1.0 - c)) / max(c, 1e-4), 0.0, 1.0) * c;
  }
  Number erosion = u_cloud.erosion;
  if (CV_MODE_DETAIL > 0.5 && erosion > 0.0 && base > 0.0) {
    vec3 dv = vec3(v.y, v.z, v.w);
    if (CV_MODE_CURL > 0.5) {
      // The detail is read where the curl field moves it (motion.curl_*): the base shape stays.
      vec3 off = curl_detail_offset_m(uvw, seen_h, u_cloud.curl_repeats, u_cloud.curl_shift, u_cloud.curl_amplitude_m);
      vec3 q = uvw + off / volume_uvw_extent_m();
      vec4 w = CV_MODE_EXACT_FILTER > 0.5 ? volume_trilinear(q) : volume_filtered(q);
      dv = vec3(w.y, w.z, w.w);
    }
    // Wispy (inverted detail) near the cloud base, billowy higher up (cloudgen/erosion.glsl): a
    // rule of the altitude, so taken where the sample is seen, not where the moving cloud came from
    // (a baked motion frame, which moves the channels, then erodes exactly like the moving volume).
    Number e = erosion_threshold(erosion_detail(dv.x, dv.y, dv.z), seen_h, erosion);
    base = eroded_base(base, e);
  }
  if (CV_MODE_FINE_DETAIL > 0.5 && base > 0.0) base = eroded_base(base, fine_detail_threshold(uvw, seen_h));
  return max(base, 0.0) * u_cloud.density_scale;
}
Number cloud_density(vec3 p) {
  vec3 motion = motion_at(p);
  return cloud_density_seen(p, motion, moving_uvw(p, motion));
}

// Occupancy of the coarse cell that holds the static position seen at camera-relative p. The march only asks about
// points inside the box, so indices are clamped (wrapped in x/z for tiling volumes): a ray entering
// through a face must see that face's cell even when rounding puts the point a hair outside, or a
// large step could skip a whole corner of a dense boundary cell.
//
// Moving clouds in box mode read instead the grid make_frame builds over the march box for this
// time (occupancy_texel then serves that grid): a cell is marked when the static cells its points
// can be displaced from lie within one cell of density (frame.cpp build_moved_occupancy). Marked
// wherever density, or density a large step away, can be, and no motion-table read (on llvmpipe those reads were nearly all
// of what moving clouds cost the thesis path: docs/motion.md).
// The cell of that moved grid holding p (clamped into it), for occupied() (the thesis scheme;
// distance jumps read the still field at the static point seen, lighting.glsl empty_cells_seen).
bool moved_grid() { return CV_MODE_MOTION > 0.5 && !layer_mode(); }
ivec3 moved_cell(vec3 p) {
  ivec3 m = ivec3(floor((p - u_cloud.march_min_m) / u_cloud.moved_occ_cell_m));
  ivec3 mn = ivec3(u_cloud.moved_occ_dims);
  return ivec3(clamp_index(m.x, mn.x), clamp_index(m.y, mn.y), clamp_index(m.z, mn.z));
}
// The static coarse cell holding volume coordinates uvw. A tiling volume repeats every volume_dims
// voxels (the texture's GL_REPEAT), so x and z wrap there, in voxels, before the cell is found: a
// cell edge that does not divide the tile leaves a narrower last cell, and wrapping cell indices
// instead would put every repeat but the first in the wrong cells (the thesis scheme then skipped
// density in layer mode). Clamped, so a point a rounding outside the grid reads its edge cell.
ivec3 static_cell(vec3 uvw) {
  vec3 v = uvw * u_cloud.volume_dims;
  if (CV_MODE_TILES > 0.5) {
    v.x -= u_cloud.volume_dims.x * floor(v.x / u_cloud.volume_dims.x);
    v.z -= u_cloud.volume_dims.z * floor(v.z / u_cloud.volume_dims.z);
  }
  ivec3 cell = ivec3(floor(v / u_cloud.occ_cell_voxels));
  ivec3 n = ivec3(u_cloud.occ_dims);
  return ivec3(clamp_index(cell.x, n.x), clamp_index(cell.y, n.y), clamp_index(cell.z, n.z));
}
bool occupied(vec3 p) {
  if (moved_grid()) return occupancy_texel(moved_cell(p)) > 0.5;
  return occupancy_texel(static_cell(moving_uvw(p, motion_at(p)))) > 0.5;
}
