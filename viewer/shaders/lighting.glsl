// Lighting of the medium and the ground: Beer-Lambert with the powder term (Hogfeldt 2016, thesis
// 2.5), energy-conserving step integration (S. Hillaire, "Physically Based and Unified Volumetric
// Rendering in Frostbite", SIGGRAPH 2015), the light march toward the sun, cloud shadows on the
// ground, and the distance field's empty radius (the primary, light and shadow marches skip by it).
// Needs common.glsl, phase.glsl, medium.glsl and `u_cloud`.

// Distance skipping (render.skipping=distance, docs/viewer-speed.md): the coarse grid's distance
// field d (L-infinity cells to the nearest cell that holds density, before padding; exact,
// volume_prep.cpp) at the cell holding p, found like occupied() finds its cell. A cell at distance
// d >= 1 is separated from every cell holding density by d - 1 whole cells, and trilinear density
// reaches half a voxel (df_margin_m) past such a cell, so no point within (d - 1) * cell - margin of
// any point of that cell (in L-infinity, so along any straight segment) has density > 0.
//
// Moving clouds read the same still field at the static point seen, q = p - D(h(p)), as the
// density does, box and layer mode alike; empty_radius_of shortens the radius by the motion's
// stretch. (In box mode q may lie outside the volume: static_cell clamps it onto the nearest cell,
// and no density point is nearer to q than to that cell, in L-infinity, so its radius holds.)
// `uvw`: moving_uvw(p, motion_at(p)), which the primary march has already found for the sample's
// density.
int empty_cells_seen(vec3 uvw) { return distance_texel(static_cell(uvw)); }
int empty_cells(vec3 p) { return empty_cells_seen(moving_uvw(p, motion_at(p))); }

// The distance from p within which the density is provably 0 (metres; 0 next to density).
// The bound holds in L-infinity, so along any straight segment. In layer mode a straight ray bends
// away from the layer's flat texture coordinates by at most r^2 / 2R (layer_altitude): r - r^2 / 2R
// plus that bend stays within r.
// r: metres around the static point seen that hold no density; the radius a march may jump by.
Number empty_radius_m(Number r) {
  if (layer_mode()) r -= r * r / (2.0 * u_cloud.earth_radius_m);
  // Moving clouds read the field at the static point seen, q = p - D(h(p)), which
  // moves up to motion_stretch times as fast as p (1 when still): a jump of r / stretch keeps q
  // within r. (The bend's effect on h, and so on D, is second order: G/H x J^2/2R, metres against
  // the 0.1% of r the march leaves; the field is at most half a tile across.)
  return max(r, 0.0) / max(u_cloud.motion_stretch, 1.0);
}
Number empty_radius_of(int d) {
  if (d <= 1) return 0.0;
  return empty_radius_m(Number(d - 1) * u_cloud.df_cell_m - u_cloud.df_margin_m);
}

// Tree skipping (render.skipping=tree, volume=nanovdb): instead of the field, the NanoVDB tree's
// empty node around the static point seen (volume_nanovdb.glsl nanovdb_empty_box): a hierarchical
// DDA, each check one walk down the tree, each jump to where the ray leaves that node's empty
// box. No distance field. `uvw` as for empty_cells_seen.
// A box open past the volume's sides gives no bound: jumps stop at 1000 km (the march's end comes
// first; the jump count stays an int).
#define CV_TREE_MAX_JUMP_M 1e6
vec3 tree_position(vec3 uvw) {
  vec3 x = uvw * u_cloud.volume_dims;
  if (CV_MODE_TILES > 0.5) {
    x.x -= u_cloud.volume_dims.x * floor(x.x / u_cloud.volume_dims.x);
    x.z -= u_cloud.volume_dims.z * floor(x.z / u_cloud.volume_dims.z);
  }
  return x;
}
// Any direction (the light and shadow marches, and the primary march in layer mode, where the ray
// bends through the texture's coordinates): the L-infinity margin
// to the box's faces, in voxels of the smallest world edge (df_cell_m / occ_cell_voxels), so that
// any straight segment that short stays in the box.
Number tree_radius_seen(vec3 uvw) {
  vec3 x = tree_position(uvw);
  vec3 lo = vec3(0.0), hi = vec3(0.0);
  if (!nanovdb_empty_box(x, lo, hi)) return 0.0;
  vec3 m = min(x - lo, hi - x);
  Number r = min(m.x, min(m.y, m.z)) * (u_cloud.df_cell_m / u_cloud.occ_cell_voxels);
  return empty_radius_m(min(r, CV_TREE_MAX_JUMP_M));
}
// The primary march in box mode: the distance along unit `rd` to where the static point seen
// leaves the box (the DDA's exit), in metres. Still clouds: the ray is straight in voxel
// coordinates, v voxels per metre. Moving clouds: the static point is q = p - D(h(p)), and along a
// jump of J metres h changes by at most J |rd.y| / H, so D by at most J |rd.y| (stretch - 1)
// (apply_motion's G / H): q's voxel coordinate along each axis moves at J v, give or take
// J e. The exit bounds both sides. (Layer mode bends the ray in the texture: the radius above.)
Number tree_exit_seen(vec3 uvw, vec3 rd) {
  if (layer_mode()) return tree_radius_seen(uvw);
  vec3 x = tree_position(uvw);
  vec3 lo = vec3(0.0), hi = vec3(0.0);
  if (!nanovdb_empty_box(x, lo, hi)) return 0.0;
  vec3 voxel = u_cloud.volume_size_m / u_cloud.volume_dims;
  vec3 v = rd / voxel;  // voxels per metre along the ray
  vec3 e = vec3(max(u_cloud.motion_stretch, 1.0) - 1.0) * abs(rd.y) / voxel;
  Number t = CV_TREE_MAX_JUMP_M;
  for (int a = 0; a < 3; ++a) {
    if (v[a] + e[a] > 0.0) t = min(t, (hi[a] - x[a]) / (v[a] + e[a]));
    if (e[a] - v[a] > 0.0) t = min(t, (x[a] - lo[a]) / (e[a] - v[a]));
  }
  return t;
}
Number empty_radius(vec3 p) {
  if (CV_MODE_SKIP_TREE > 0.5) return tree_radius_seen(moving_uvw(p, motion_at(p)));
  return empty_radius_of(empty_cells(p));
}

// Beer-Lambert transmittance of optical depth tau (dimensionless).
Number beer_lambert(Number tau) { return exp(-tau); }

// Powder / multiple-scattering approximation of the thesis (2.5): 1 - exp(-c*d).
Number powder_term(Number tau, Number c) { return 1.0 - exp(-c * tau); }

// Hillaire 2015: in-scattering over a homogeneous step of length dt, relative to the transmittance
// at the step's start: integral_0^dt S*sigma_s*exp(-sigma_t*s) ds = sigma_s*S*(1-exp(-sigma_t*dt))/sigma_t.
// Converges to the exact integral as dt shrinks instead of over-brightening thick steps like S*dt.
vec3 integrate_step(vec3 source, Number sigma_s, Number sigma_t, Number dt) {
  if (sigma_t <= 0.0) return source * sigma_s * dt;
  return source * (sigma_s * (1.0 - exp(-sigma_t * dt)) / sigma_t);
}

// Optical depth toward the sun from p: `light_samples` samples, the first step `light_step_m`,
// each next step `light_growth` times longer (thesis 2.5: few samples, reaching far).
Number light_optical_depth(vec3 p) {
  vec3 sun = u_cloud.sun_dir;
  int samples = int(u_cloud.light_samples);
  Number step_len = u_cloud.light_step_m;
  Number growth = u_cloud.light_growth;
  bool skip_empty = int(CV_MODE_LIGHT) == CV_LIGHT_MARCH_SKIP_EMPTY;
  bool by_distance = skip_empty && CV_MODE_DF_LIGHT > 0.5;
  Number s = 0.0;
  Number tau = 0.0;
  Number empty_until = -1.0;  // distance field: samples before this distance along the ray are empty
  // Box mode: the march ends where the ray leaves the (marched) box. A tiling texture repeats
  // beyond it, but the scene holds one box of cloud: the path tracer, the ground's cloud shadows
  // and the primary march see nothing outside it, so the sun's light must not either (marching the
  // repeats darkened a tiling cloud's sunlit side: 5% of the thesis cloud's light at sunset).
  Number t_exit = CV_NO_HIT;
  if (!layer_mode()) {
    vec3 bmin = u_cloud.march_min_m - p;
    t_exit = ray_box(sun, bmin, bmin + u_cloud.march_size_m).y;
  }
  for (int i = 0; i < samples; ++i) {
    Number at = s + 0.5 * step_len;
    if (at > t_exit) break;
    vec3 q = p + sun * at;
    // The same coarse grid also spares the light march its texture reads in empty cells, where
    // the density is exactly 0 (an addition to the thesis, `render.occupancy_light`); the distance
    // field spares it the reads of every sample within one empty radius of a read.
    if (by_distance) {
      if (at >= empty_until) {
        Number r = empty_radius(q);
        if (r > 0.0) empty_until = at + 0.999 * r;
        else tau += cloud_density(q) * u_cloud.sigma_t_per_m * step_len;
      }
    } else if (!skip_empty || occupied(q)) {
      tau += cloud_density(q) * u_cloud.sigma_t_per_m * step_len;
    }
    s += step_len;
    step_len *= growth;
  }
  return tau;
}

// Light volume (render.light_volume): the optical depth of light_optical_depth at the centres of a
// light_volume_dims grid over the box, built once per sun / volume / lighting change (the
// light_volume pass; the CPU reference builds the same grid in double precision), then looked up
// trilinearly instead of marching. Box mode only (layer mode's coverage map does not repeat with
// the texture). The grid spans the march box: the volume's box for still clouds; while they move,
// the box grown by the motion's reach, and the grid is rebuilt every frame from the moving density
// (make_frame decides when that pays). The texel's position in camera-relative metres:
vec3 light_volume_position(ivec3 texel) {
  return u_cloud.march_min_m + (vec3(texel) + 0.5) / u_cloud.light_volume_dims * u_cloud.march_size_m;
}

// The value a light-volume texel holds: the light march from its centre. Only cloud samples of
// density > 0 read the grid (the lighting and the diffusion source), each the eight texels whose
// centres lie within one texel spacing of it along every axis. So with distance skipping on, a
// texel whose empty radius exceeds that spacing is never read, and keeps 0 instead of a march:
// the image does not change. A tiling volume's grid wraps in x and z, and the moved grid's field
// does not: there the texels of the wrapping faces are always marched.
Number light_volume_value(ivec3 texel) {
  vec3 p = light_volume_position(texel);
  if (CV_MODE_SKIP_DISTANCE > 0.5) {
    vec3 spacing = u_cloud.march_size_m / u_cloud.light_volume_dims;
    ivec3 n = ivec3(u_cloud.light_volume_dims);
    bool face = CV_MODE_TILES > 0.5 && (texel.x == 0 || texel.z == 0 || texel.x == n.x - 1 || texel.z == n.z - 1);
    if (!face && empty_radius(p) > 1.001 * max(spacing.x, max(spacing.y, spacing.z))) return 0.0;
  }
  return light_optical_depth(p);
}

// Trilinear from texel fetches, wrapped in x/z for tiling volumes, clamped otherwise (the texture
// unit's GL_LINEAR with the light volume's wrap modes; exact_filter and the CPU reference), of the
// light volume (ms = false: its value in x) or the multiple-scattering volume (ms = true).
vec4 grid_trilinear(bool ms, vec3 uvw) {
  ivec3 n = ivec3(ms ? u_cloud.ms_volume_dims : u_cloud.light_volume_dims);
  bool tiles = !ms && CV_MODE_TILES > 0.5;  // the diffusion volume never wraps (see ms_volume_source)
  TrilinearCell cell = trilinear_cell(uvw, n);
  ivec3 i0 = cell.i0;
  vec3 f = cell.f;
  vec4 acc = vec4(0.0);
  for (int k = 0; k < 8; ++k) {
    ivec3 c = trilinear_corner(i0, k, n, tiles);
    acc += trilinear_weight(f, k) * (ms ? ms_volume_texel(c) : vec4(light_volume_texel(c), 0.0, 0.0, 0.0));
  }
  return acc;
}

Number light_volume_tau(vec3 p) {
  vec3 uvw = (p - u_cloud.march_min_m) / u_cloud.march_size_m;  // volume_uvw(p) while still
  return CV_MODE_EXACT_FILTER > 0.5 ? grid_trilinear(false, uvw).x : light_volume_filtered(uvw);
}

// The optical depth toward the sun from p as the lighting uses it: 0 without the light march, the
// light volume's lookup or the march itself.
Number sun_optical_depth(vec3 p) {
  if (int(CV_MODE_LIGHT) == CV_LIGHT_OFF) return 0.0;
  return CV_MODE_LIGHT_VOLUME > 0.5 ? light_volume_tau(p) : light_optical_depth(p);
}

// Multiple scattering by flux-limited diffusion (render.ms_volume; Koerner et al., "Flux-Limited
// Diffusion for Multiple Scattering in Participating Media", CGF 2014; docs/accuracy.md): the
// fluence phi of the light that has scattered at least once, solved on a coarse ms_volume_dims grid
// over the box (ms_diffusion.cpp, the same C++ solver for both renderers) from each cell's mean
// extinction and first-scattering source, which this pass computes. Per unit sun irradiance:
//   x: the cell's mean sigma_t (1/m), y: its mean sigma_t * exp(-tau_sun) (1/m; times the albedo
//   it is the source of scattered light),
// over CV_MS_SUBSAMPLES^3 stratified points (a cell is optically thick: its centre alone would
// misjudge how much sunlight it catches). The box is lit as one cloud even when its texture tiles:
// light that leaves it sideways is gone, as in the path tracer, so the solve sees vacuum there.
vec3 ms_volume_position(vec3 cell_coord) {
  return u_cloud.volume_min_m + cell_coord / u_cloud.ms_volume_dims * u_cloud.volume_size_m;
}
vec2 ms_volume_source(ivec3 cell) {
  vec2 acc = vec2(0.0);
  const int m = CV_MS_SUBSAMPLES;
  for (int k = 0; k < m * m * m; ++k) {
    vec3 o = (vec3(Number(k % m), Number((k / m) % m), Number(k / (m * m))) + 0.5) / Number(m);
    vec3 p = ms_volume_position(vec3(cell) + o);
    Number sigma = cloud_density(p) * u_cloud.sigma_t_per_m;
    if (sigma > 0.0) acc += vec2(sigma, sigma * beer_lambert(sun_optical_depth(p)));
  }
  return acc / Number(m * m * m);
}

// The multiply scattered radiance at p toward `to_eye` per unit sun irradiance and unit sigma_s:
// the P1 (diffusion) radiance phi / 4 pi + 3 F . w / 4 pi through the phase function, whose first
// moment is g: (phi + 3 g F . to_eye) / 4 pi. The flux term brightens the light leaving a surface
// toward the viewer (at a face to vacuum F is phi / 2 outward: +45% at g 0.3).
Number ms_volume_radiance(vec3 p, vec3 to_eye) {
  vec3 uvw = volume_uvw(p);
  vec4 t = CV_MODE_EXACT_FILTER > 0.5 ? grid_trilinear(true, uvw) : ms_volume_filtered(uvw);
  return max(t.x + dot(vec3(t.y, t.z, t.w), to_eye), 0.0) / (4.0 * CV_PI);
}

// Multiple scattering by octaves (Wrenninge et al., "Oz: The Great and Volumetric", SIGGRAPH 2013
// talk; Hillaire, "Physically Based Sky, Atmosphere and Cloud Rendering in Frostbite", 2016): the
// sun term is summed over render.ms_octaves octaves, octave i with weight a^i, optical depth scaled
// by b^i and phase eccentricity by c^i (a, b, c = ms_attenuation, ms_extinction, ms_eccentricity;
// a <= b keeps it energy-conserving). The phases of one camera ray for octaves 1..3:
// Henyey-Greenstein with g c, g c^2, g c^3 (octave 0's is the phase function itself, per colour
// channel: phase_function_rgb).
vec3 octave_phases(Number cos_theta) {
  Number c = u_cloud.ms_eccentricity;
  Number g = u_cloud.hg_g;
  return vec3(phase_hg(cos_theta, g * c), phase_hg(cos_theta, g * c * c), phase_hg(cos_theta, g * c * c * c));
}

// The ambient sky light at p, isotropic (the phase function integrates to 1, so it scatters as it
// is): the sky's radiance from above at the top of the clouds, the light from below (ground and air)
// at their base, mixed by the height fraction in the box (layer mode: in the layer), a proxy for
// which half of the sphere the cloud itself hides (Schneider's Nubis ambient gradient).
vec3 ambient_radiance(vec3 p) {
  Number h = clamp(height_fraction(p), 0.0, 1.0);
  return mix(u_cloud.ambient_below_color, u_cloud.ambient_color, h) * u_cloud.ambient_scale;
}

// Radiance scattered toward the viewer at p per unit sigma_s: sun irradiance * (phase *
// Beer(tau), plus orders >= 2 from the octaves or the diffusion volume) * powder mix + ambient sky radiance. phase0: the phase
// function per channel (phase_function_rgb); phases: octaves 1..3's (octave_phases); rd: the
// view ray's direction.
vec3 inscattered_radiance(vec3 p, vec3 rd, vec3 phase0, vec3 phases) {
  Number tau = sun_optical_depth(p);
  Number powder = mix(1.0, powder_term(tau, u_cloud.powder_c), u_cloud.powder_strength);
  Number higher = 0.0;
  int octaves = int(CV_MODE_MS_OCTAVES);
  if (CV_MODE_MS_VOLUME > 0.5) {
    higher = ms_volume_radiance(p, -rd);  // orders >= 2 from the diffusion solve, instead of the octaves
  } else if (octaves > 1) {
    Number a = u_cloud.ms_attenuation, b = u_cloud.ms_extinction;
    higher += a * phases.x * beer_lambert(tau * b);
    if (octaves > 2) higher += a * a * phases.y * beer_lambert(tau * b * b);
    if (octaves > 3) higher += a * a * a * phases.z * beer_lambert(tau * b * b * b);
  }
  vec3 transfer = phase0 * beer_lambert(tau) + vec3(higher);
  vec3 sun = sun_color_at(p) * transfer * (u_cloud.sun_radiance * powder);
  return sun + ambient_radiance(p);
}

// Transmittance of the clouds toward the sun from a ground point p (fixed-step march, for shadows).
Number sun_shadow_transmittance(vec3 p) {
  vec3 sun = u_cloud.sun_dir;
  vec3 bmin = u_cloud.march_min_m - p;
  vec3 bmax = bmin + u_cloud.march_size_m;
  vec2 tb = layer_mode() ? shell_interval(p, sun) : ray_box(sun, bmin, bmax);
  if (layer_mode()) tb.y = min(tb.y, tb.x + 20000.0);  // shadows from within 20 km
  if (!(tb.y > tb.x)) return 1.0;
  int samples = int(u_cloud.shadow_samples);
  Number seg = (tb.y - tb.x) / Number(samples);
  Number tau = 0.0;
  bool by_distance = CV_MODE_DF_LIGHT > 0.5;
  Number empty_until = -1.0;  // as in light_optical_depth: samples before this are provably empty
  for (int i = 0; i < samples; ++i) {
    Number at = tb.x + (Number(i) + 0.5) * seg;
    vec3 q = p + sun * at;
    if (by_distance) {
      if (at < empty_until) continue;
      Number r = empty_radius(q);
      if (r > 0.0) {
        empty_until = at + 0.999 * r;
        continue;
      }
    }
    tau += cloud_density(q);
  }
  return exp(-tau * seg * u_cloud.sigma_t_per_m);
}

// Ground shadow map (render.shadow_map, box mode): sun_shadow_transmittance at the centres of a
// grid of ground texels (the shadow_map pass; the CPU reference builds the same grid in double
// precision), then looked up bilinearly from texel fetches (the same arithmetic on GL and CPU)
// instead of marching per ground pixel. A point outside the grid's area sends its sun ray past
// the march box: 1 exactly, as the march gives. The texel centre on the ground, camera-relative:
vec3 shadow_map_position(ivec2 texel) {
  return vec3(u_cloud.march_min_m.x + u_cloud.shadow_map_min_x_m + (Number(texel.x) + 0.5) * u_cloud.shadow_map_texel_m,
              u_cloud.ground_y_m,
              u_cloud.march_min_m.z + u_cloud.shadow_map_min_z_m + (Number(texel.y) + 0.5) * u_cloud.shadow_map_texel_m);
}

Number shadow_map_lookup(vec3 p) {
  ivec2 n = ivec2(int(u_cloud.shadow_map_nx), int(u_cloud.shadow_map_nz));
  vec2 x = vec2(p.x - u_cloud.march_min_m.x - u_cloud.shadow_map_min_x_m,
                p.z - u_cloud.march_min_m.z - u_cloud.shadow_map_min_z_m) / u_cloud.shadow_map_texel_m - 0.5;
  if (x.x < -0.5 || x.y < -0.5 || x.x > Number(n.x) - 0.5 || x.y > Number(n.y) - 0.5) return 1.0;
  vec2 fl = floor(x);
  vec2 f = x - fl;
  ivec2 i0 = clamp(ivec2(fl), ivec2(0), n - 1);
  ivec2 i1 = clamp(ivec2(fl) + 1, ivec2(0), n - 1);
  Number a = mix(shadow_map_texel(ivec2(i0.x, i0.y)), shadow_map_texel(ivec2(i1.x, i0.y)), f.x);
  Number b = mix(shadow_map_texel(ivec2(i0.x, i1.y)), shadow_map_texel(ivec2(i1.x, i1.y)), f.x);
  return mix(a, b, f.y);
}

// The clouds' shadow at the ground point p: the map's lookup or the march.
Number ground_shadow(vec3 p) {
  return CV_MODE_SHADOW_MAP > 0.5 ? shadow_map_lookup(p) : sun_shadow_transmittance(p);
}

// Lambertian ground with a gentle 8 km albedo variation (no thin lines: they would alias),
// lit by the sun (shadowed by the clouds) and the ambient sky.
vec3 ground_radiance(vec3 p) {
  vec3 sun = u_cloud.sun_dir;
  Number mu = max(sun.y, 0.0);
  Number wx = u_cloud.camera_world_mod_m.x + p.x;
  Number wz = u_cloud.camera_world_mod_m.z + p.z;
  Number variation = 0.5 + 0.25 * (sin(wx * (CV_PI / 4096.0)) + sin(wz * (CV_PI / 4096.0)));
  vec3 albedo = vec3(0.10, 0.12, 0.07) * (u_cloud.ground_albedo / 0.18) * (0.9 + 0.2 * variation);
  Number shadow = mu > 0.0 ? ground_shadow(p) : 0.0;
  vec3 irradiance = sun_color_at(p) * (u_cloud.sun_radiance * mu * shadow)
                  + u_cloud.ambient_color * (u_cloud.ambient_scale * CV_PI);
  return albedo * irradiance / CV_PI;
}
