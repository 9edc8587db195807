// Cloud marching and lighting math, written once in the subset of GLSL that C++ also compiles.
// The GL passes include it after prelude_glsl.glsl; src/reference.cpp includes it inside a C++
// class with double-precision glm types (Bruneton & Neyret's functions.glsl / reference/functions.cc).
//
// Implements:
//  - R. Hogfeldt, "Convincing Cloud Rendering", and R. Olajos, "Real-Time Rendering of Volumetric
//    Clouds", Lund University 2016 (seed 000): ray marching with a jittered start, occupancy skipping
//    (large steps through empty coarse cells, step back one large step on entering an occupied cell,
//    re-check after the small steps add up to one large step), adaptive step, light march toward the
//    sun, Beer-Lambert x powder term, Henyey-Greenstein vs a Mie phase table, Reinhard tone mapping.
//  - S. Hillaire, "Physically Based and Unified Volumetric Rendering in Frostbite", SIGGRAPH 2015:
//    energy-conserving integration of each step, S*(1 - exp(-sigma_t*dt))/sigma_t.
//  - A. Schneider, "The Real-Time Volumetric Cloudscapes of Horizon Zero Dawn", SIGGRAPH 2015
//    (seed 001): base shape R eroded by the G/B/A detail fBm with a remap.
//
// The including side provides: the types Number/vec2/vec3/vec4/ivec2/ivec3/uint, the IN/OUT
// macros, `CloudParams u_cloud` (cloud_params.glsl) and four lookups:
//   vec4   volume_texel(ivec3 texel)     texel of the RGBA volume, texel inside the grid
//   vec4   volume_filtered(vec3 uvw)     filtered lookup (the GPU's texture unit; exact on the CPU)
//   Number occupancy_texel(ivec3 cell)   1 where the coarse cell may hold density, else 0
//   Number mie_table_value(int i)        i-th entry of the Mie phase table over theta in [0, pi]
//   vec2   coverage_texel(ivec2 texel)   layer coverage map: R coverage, G cloud type, in [0, 1]
//   ivec2  coverage_size()               size of the coverage map in texels
// Constants are macros, not globals, so that the file also works inside a C++ class body.

#define CV_PI 3.14159265358979323846
#define CV_TRANSMITTANCE_EPSILON 1e-3

// ---------------------------------------------------------------- phase functions (1/sr)

// Henyey-Greenstein; integrates to 1 over the sphere for |g| < 1.
Number phase_hg(Number cos_theta, Number g) {
  Number g2 = g * g;
  Number denom = 1.0 + g2 - 2.0 * g * cos_theta;
  return (1.0 - g2) / (4.0 * CV_PI * denom * sqrt(denom));
}

Number phase_isotropic() { return 1.0 / (4.0 * CV_PI); }

// Table over theta = 0..pi in `u_cloud.phase.z` equal steps, linear interpolation, already
// normalised to integrate to 1 over the sphere. Interpolated by hand on both sides so the GPU and
// the CPU agree to float precision.
Number phase_mie(Number cos_theta) {
  int n = int(u_cloud.phase.z);
  Number x = acos(clamp(cos_theta, -1.0, 1.0)) / CV_PI * Number(n - 1);
  int i = min(int(floor(x)), n - 2);
  Number f = x - Number(i);
  return mix(mie_table_value(i), mie_table_value(i + 1), f);
}

// phase.x: 0 = "none" (isotropic, the thesis's no-phase baseline), 1 = HG(g), 2 = Mie table.
Number phase_function(Number cos_theta) {
  int mode = int(u_cloud.phase.x);
  if (mode == 1) return phase_hg(cos_theta, Number(u_cloud.phase.y));
  if (mode == 2) return phase_mie(cos_theta);
  return phase_isotropic();
}

// ---------------------------------------------------------------- attenuation terms

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

// ---------------------------------------------------------------- hashing and jitter

// PCG hash (Jarzynski & Olano 2020) on unsigned 32-bit integers: wraps identically in GLSL and C++.
uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Jitter of the first sample in [0, 1), per pixel (GL window coordinates) and per frame.
// 24 bits so the value is exact in float and double.
Number jitter_offset(ivec2 pixel, int frame) {
  uint h = pcg_hash(uint(pixel.x) + pcg_hash(uint(pixel.y) + pcg_hash(uint(frame))));
  return Number(h >> 8u) / 16777216.0;
}

// ---------------------------------------------------------------- geometry

// Entry and exit distances of a ray from the origin along unit `rd` through the box [bmin, bmax];
// entry clamped to 0 (camera inside). No hit when x >= y.
vec2 ray_box(vec3 rd, vec3 bmin, vec3 bmax) {
  vec3 inv = 1.0 / rd;
  vec3 ta = bmin * inv;
  vec3 tb = bmax * inv;
  vec3 tmin = min(ta, tb);
  vec3 tmax = max(ta, tb);
  Number t_near = max(max(tmin.x, tmin.y), tmin.z);
  Number t_far = min(min(tmax.x, tmax.y), tmax.z);
  return vec2(max(t_near, 0.0), t_far);
}

// ---------------------------------------------------------------- volume sampling

// GLSL leaves % undefined for negative operands (C++ truncates): keep both operands non-negative.
int wrap_index(int i, int n) { return i >= 0 ? i % n : (n - 1) - ((-i - 1) % n); }
int clamp_index(int i, int n) { return min(max(i, 0), n - 1); }

// Trilinear filter done by hand from texel fetches: texel centres at (i + 0.5) / n, x and z
// wrapped for tileable volumes, clamped otherwise (GL_REPEAT / GL_CLAMP_TO_EDGE semantics).
vec4 volume_trilinear(vec3 uvw) {
  ivec3 n = ivec3(vec3(u_cloud.volume_dims));
  bool tiles = u_cloud.volume_size.w > 0.5;
  vec3 x = uvw * vec3(n) - 0.5;
  vec3 fl = floor(x);
  vec3 f = x - fl;
  ivec3 i0 = ivec3(fl);
  vec4 acc = vec4(0.0);
  for (int k = 0; k < 8; ++k) {
    ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    ivec3 i = i0 + o;
    i.x = tiles ? wrap_index(i.x, n.x) : clamp_index(i.x, n.x);
    i.y = clamp_index(i.y, n.y);
    i.z = tiles ? wrap_index(i.z, n.z) : clamp_index(i.z, n.z);
    vec3 w = mix(vec3(1.0) - f, f, vec3(o));
    acc += (w.x * w.y * w.z) * volume_texel(i);
  }
  return acc;
}

// ---------------------------------------------------------------- layer mode
// Horizon Zero Dawn style (Schneider 2015, seed 001): the tileable texture repeats over a cloud
// layer between two altitudes over a curved Earth; a 2D coverage map says where clouds are and
// the cloud-type height gradient shapes their profile.

bool layer_mode() { return u_cloud.layer.x > 0.5; }

// Altitude above the ground sphere of camera-relative p. Parabolic Earth: the exact
// sqrt(r^2 + (R + h)^2) - R loses everything to float rounding at R = 6360 km, while
// h + y + (x^2 + z^2) / 2R is exact to d^4/(8 R^3) (2 m at 200 km) and well conditioned.
Number layer_altitude(vec3 p) {
  return Number(u_cloud.layer2.x) + p.y + (p.x * p.x + p.z * p.z) / (2.0 * Number(u_cloud.layer.w));
}

// Roots of a t^2 + b t + c = 0 (a >= 0), sorted; (1e30, -1e30) when there are none.
// The stable form (q = -(b + sign(b) sqrt(D)) / 2; roots c/q and q/a) avoids cancellation.
vec2 parabola_roots(Number a, Number b, Number c) {
  Number aa = max(a, 1e-12);
  Number disc = b * b - 4.0 * aa * c;
  if (disc < 0.0) return vec2(1e30, -1e30);
  Number s = sqrt(disc);
  Number q = -0.5 * (b + (b >= 0.0 ? s : -s));
  Number r1 = q != 0.0 ? c / q : 0.0;
  Number r2 = q / aa;
  return vec2(min(r1, r2), max(r1, r2));
}

// The part [t0, t1] of the ray p + t d (t >= 0) inside the cloud layer, up to the first time it
// leaves (empty when x >= y). Altitude along the ray is the convex parabola a0 + a1 t + a2 t^2.
vec2 shell_interval(vec3 p, vec3 d) {
  Number R = Number(u_cloud.layer.w);
  Number bottom = Number(u_cloud.layer.y);
  Number top = Number(u_cloud.layer.z);
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
  Number period = Number(u_cloud.layer3.w);
  vec2 x = vec2((Number(u_cloud.layer4.x) + p.x) / period * Number(n.x) - 0.5,
                (Number(u_cloud.layer4.y) + p.z) / period * Number(n.y) - 0.5);
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

// Height gradient of a cloud type at normalised layer height h: 0 stratus (low, thin),
// 0.5 cumulus, 1 cumulonimbus (the full layer) (Schneider 2015).
Number cloud_type_gradient(Number h, Number type) {
  Number stratus = smoothstep(0.0, 0.05, h) * (1.0 - smoothstep(0.1, 0.25, h));
  Number cumulus = smoothstep(0.0, 0.1, h) * (1.0 - smoothstep(0.4, 0.65, h));
  Number cumulonimbus = smoothstep(0.0, 0.1, h) * (1.0 - smoothstep(0.75, 1.0, h));
  if (type < 0.5) return mix(stratus, cumulus, type * 2.0);
  return mix(cumulus, cumulonimbus, type * 2.0 - 1.0);
}

// Normalised volume coordinates of a camera-relative position: the box, or in layer mode the
// repeating tile horizontally and the layer's height vertically.
vec3 volume_uvw(vec3 p) {
  if (layer_mode()) {
    Number h = (layer_altitude(p) - Number(u_cloud.layer.y)) / Number(u_cloud.layer.z - u_cloud.layer.y);
    return vec3((Number(u_cloud.layer2.y) + p.x) / Number(u_cloud.layer3.x), h,
                (Number(u_cloud.layer2.z) + p.z) / Number(u_cloud.layer3.z));
  }
  return (p - vec3(u_cloud.volume_min)) / vec3(u_cloud.volume_size);
}

// Cloud density (dimensionless, >= 0) at camera-relative position p: base shape R, eroded by the
// G/B/A detail fBm (HZD remap), scaled by the density multiplier. Zero outside the box (x and z
// repeat for tileable volumes). Erosion only lowers density, so the occupancy grid built from R
// stays conservative.
Number cloud_density(vec3 p) {
  vec3 uvw = volume_uvw(p);
  if (uvw.y < 0.0 || uvw.y > 1.0) return 0.0;
  bool tiles = u_cloud.volume_size.w > 0.5;
  if (!tiles && (uvw.x < 0.0 || uvw.x > 1.0 || uvw.z < 0.0 || uvw.z > 1.0)) return 0.0;
  vec4 v = u_cloud.control.z > 0.5 ? volume_trilinear(uvw) : volume_filtered(uvw);
  Number base = v.x;
  if (layer_mode()) {
    // Coverage remap (HZD): raise the threshold where coverage is low, then scale by coverage.
    // Like erosion it only lowers density, so the texture's occupancy grid stays conservative.
    vec2 cov = coverage_at(p);
    Number c = clamp(cov.x + Number(u_cloud.layer4.z), 0.0, 1.0);
    Number type = u_cloud.layer4.w >= 0.0 ? Number(u_cloud.layer4.w) : cov.y;
    Number x = base * cloud_type_gradient(uvw.y, type);
    base = clamp((x - (1.0 - c)) / max(c, 1e-4), 0.0, 1.0) * c;
  }
  Number erosion = Number(u_cloud.medium.y);
  if (u_cloud.volume_dims.w > 0.5 && erosion > 0.0 && base > 0.0) {
    Number detail = dot(vec3(v.y, v.z, v.w), vec3(0.625, 0.25, 0.125));
    // Wispy (inverted detail) near the cloud base, billowy higher up (Schneider 2015).
    detail = mix(1.0 - detail, detail, clamp(uvw.y * 5.0, 0.0, 1.0));
    Number e = erosion * detail;
    base = clamp((base - e) / max(1.0 - e, 1e-4), 0.0, 1.0);
  }
  return max(base, 0.0) * Number(u_cloud.medium.z);
}

// Occupancy of the coarse cell that holds camera-relative position p. The march only asks about
// points inside the box, so indices are clamped (wrapped in x/z for tiling volumes): a ray entering
// through a face must see that face's cell even when rounding puts the point a hair outside, or a
// large step could skip a whole corner of a dense boundary cell.
bool occupied(vec3 p) {
  vec3 c = volume_uvw(p) * vec3(u_cloud.volume_dims) / Number(u_cloud.occ_dims.w);
  ivec3 cell = ivec3(floor(c));
  ivec3 n = ivec3(vec3(u_cloud.occ_dims));
  bool tiles = u_cloud.volume_size.w > 0.5;
  cell.x = tiles ? wrap_index(cell.x, n.x) : clamp_index(cell.x, n.x);
  cell.y = clamp_index(cell.y, n.y);
  cell.z = tiles ? wrap_index(cell.z, n.z) : clamp_index(cell.z, n.z);
  return occupancy_texel(cell) > 0.5;
}

// ---------------------------------------------------------------- lighting

// Optical depth toward the sun from p: `light.y` samples, the first step `light.z` metres, each
// next step `light.w` times longer (thesis 2.5: few samples, reaching far).
Number light_optical_depth(vec3 p) {
  vec3 sun = vec3(u_cloud.sun_dir);
  int samples = int(u_cloud.light.y);
  Number step_len = Number(u_cloud.light.z);
  Number growth = Number(u_cloud.light.w);
  bool skip_empty = u_cloud.light.x > 1.5;
  Number s = 0.0;
  Number tau = 0.0;
  for (int i = 0; i < samples; ++i) {
    vec3 q = p + sun * (s + 0.5 * step_len);
    // The same coarse grid also spares the light march its texture reads in empty cells, where
    // the density is exactly 0 (an addition to the thesis, `render.occupancy_light`).
    if (!skip_empty || occupied(q)) tau += cloud_density(q) * Number(u_cloud.medium.x) * step_len;
    s += step_len;
    step_len *= growth;
  }
  return tau;
}

// Radiance scattered toward the viewer at p per unit sigma_s: sun irradiance * phase *
// Beer(tau) * powder mix + ambient sky radiance.
vec3 inscattered_radiance(vec3 p, Number phase) {
  Number tau = u_cloud.light.x > 0.5 ? light_optical_depth(p) : 0.0;
  Number powder = mix(1.0, powder_term(tau, Number(u_cloud.medium.w)), Number(u_cloud.phase.w));
  vec3 sun = vec3(u_cloud.sun_color) * (Number(u_cloud.sun_dir.w) * phase * beer_lambert(tau) * powder);
  // Isotropic ambient radiance: the phase function integrates to 1, so it scatters as it is.
  vec3 ambient = vec3(u_cloud.ambient_color) * Number(u_cloud.sun_color.w);
  return sun + ambient;
}

// ---------------------------------------------------------------- primary march

// Marches the camera ray along unit `rd` (camera at the origin) up to `t_scene` metres (scene depth).
// Returns (in-scattered radiance, transmittance). `iterations` counts loop trips (large or small);
// `t_mean` is the distance of the cloud weighted by opacity (for aerial perspective), 0 if none.
//
// Segments lie on the lattice t0 + n*dt (fixed step); the sample of each segment is at its start plus
// `jitter` times its length, so the jitter moves samples inside their segment and never changes the
// covered length: a uniform slab gives exactly exp(-sigma*d) for every jitter and step.
// Occupancy skipping moves by whole multiples of the small step (the large step is k small steps,
// just under one coarse cell), so the samples it keeps are the very samples of the plain march and
// the image does not change; it only skips samples whose density is zero.
vec4 march_clouds(vec3 rd, Number t_scene, Number jitter, OUT(int) iterations, OUT(Number) t_mean) {
  iterations = 0;
  t_mean = 0.0;
  Number t_weighted = 0.0;
  vec3 bmin = vec3(u_cloud.volume_min);
  vec3 bmax = bmin + vec3(u_cloud.volume_size);
  vec2 tb = layer_mode() ? shell_interval(vec3(0.0), rd) : ray_box(rd, bmin, bmax);
  Number t0 = tb.x;
  Number t1 = min(tb.y, min(t_scene, Number(u_cloud.march.z)));
  vec3 radiance = vec3(0.0);
  Number transmittance = 1.0;
  if (!(t1 > t0)) return vec4(radiance, transmittance);

  Number dt = Number(u_cloud.march.x);
  int k = max(int(u_cloud.march.y), 1);
  Number large = Number(k) * dt;
  bool adaptive = u_cloud.march2.x > 0.5;
  bool skipping = u_cloud.march2.w > 0.5;
  Number sigma_scale = Number(u_cloud.medium.x);
  Number albedo = Number(u_cloud.ambient_color.w);
  Number phase = phase_function(dot(rd, vec3(u_cloud.sun_dir)));
  int max_iterations = int(u_cloud.march.w);

  bool large_mode = skipping;
  int n = 0;            // small-step index on the fixed lattice
  Number t = t0;        // running distance for the adaptive march
  int since_check = 0;  // small steps since the coarse grid was last read
  for (int it = 0; it < max_iterations; ++it) {
    if (!adaptive) t = t0 + Number(n) * dt;
    if (t >= t1 || transmittance < CV_TRANSMITTANCE_EPSILON) break;
    iterations += 1;
    if (large_mode) {
      if (occupied(rd * t)) {
        // Entered an occupied coarse cell: step back one large step, continue with small steps.
        large_mode = false;
        since_check = 0;
        if (adaptive) t = max(t - large, t0); else n = max(n - k, 0);
      } else {
        if (adaptive) t += large; else n += k;
      }
      continue;
    }
    Number step_len = dt;
    if (adaptive) step_len = dt * (1.0 + Number(u_cloud.march2.z) * max(t - Number(u_cloud.march2.y), 0.0));
    Number seg = min(step_len, t1 - t);
    vec3 p = rd * (t + jitter * seg);
    Number density = cloud_density(p);
    if (density > 0.0) {
      Number sigma_t = density * sigma_scale;
      vec3 source = inscattered_radiance(p, phase);
      radiance += transmittance * integrate_step(source, albedo * sigma_t, sigma_t, seg);
      Number step_transmittance = exp(-sigma_t * seg);
      t_weighted += transmittance * (1.0 - step_transmittance) * (t + jitter * seg);
      transmittance *= step_transmittance;
    }
    if (adaptive) t += step_len; else n += 1;
    if (skipping) {
      since_check += 1;
      if (since_check >= k) {
        // The small steps add up to one large step: re-read the coarse grid.
        since_check = 0;
        Number t_next = adaptive ? t : t0 + Number(n) * dt;
        if (!occupied(rd * t_next)) large_mode = true;
      }
    }
  }
  if (transmittance < 1.0) t_mean = t_weighted / (1.0 - transmittance);
  return vec4(radiance, transmittance);
}

// ---------------------------------------------------------------- background

// Transmittance of the clouds toward the sun from a ground point p (fixed-step march, for shadows).
Number sun_shadow_transmittance(vec3 p) {
  vec3 sun = vec3(u_cloud.sun_dir);
  vec3 bmin = vec3(u_cloud.volume_min) - p;
  vec3 bmax = bmin + vec3(u_cloud.volume_size);
  vec2 tb = layer_mode() ? shell_interval(p, sun) : ray_box(sun, bmin, bmax);
  if (layer_mode()) tb.y = min(tb.y, tb.x + 20000.0);  // shadows from within 20 km
  if (!(tb.y > tb.x)) return 1.0;
  int samples = int(u_cloud.camera_world.w);
  Number seg = (tb.y - tb.x) / Number(samples);
  Number tau = 0.0;
  for (int i = 0; i < samples; ++i) {
    tau += cloud_density(p + sun * (tb.x + (Number(i) + 0.5) * seg));
  }
  return exp(-tau * seg * Number(u_cloud.medium.x));
}

// Lambertian ground with a gentle 8 km albedo variation (no thin lines: they would alias),
// lit by the sun (shadowed by the clouds) and the ambient sky.
vec3 ground_radiance(vec3 p) {
  vec3 sun = vec3(u_cloud.sun_dir);
  Number mu = max(sun.y, 0.0);
  Number wx = Number(u_cloud.camera_world.x) + p.x;
  Number wz = Number(u_cloud.camera_world.z) + p.z;
  Number variation = 0.5 + 0.25 * (sin(wx * (CV_PI / 4096.0)) + sin(wz * (CV_PI / 4096.0)));
  vec3 albedo = vec3(0.10, 0.12, 0.07) * (Number(u_cloud.ground.y) / 0.18) * (0.9 + 0.2 * variation);
  Number shadow = mu > 0.0 ? sun_shadow_transmittance(p) : 0.0;
  vec3 irradiance = vec3(u_cloud.sun_color) * (Number(u_cloud.sun_dir.w) * mu * shadow)
                  + vec3(u_cloud.ambient_color) * (Number(u_cloud.sun_color.w) * CV_PI);
  return albedo * irradiance / CV_PI;
}

// Simple analytic sky: horizon-to-zenith gradient and a soft sun disc (the sky issue replaces it).
vec3 sky_radiance(vec3 rd) {
  vec3 sun = vec3(u_cloud.sun_dir);
  vec3 zenith = vec3(u_cloud.sky);
  vec3 horizon = mix(zenith, vec3(1.0), 0.55);
  Number up = clamp(rd.y, 0.0, 1.0);
  vec3 sky = mix(horizon, zenith, sqrt(up));
  if (rd.y < 0.0) sky = horizon * 0.6;
  Number cos_sun = dot(rd, sun);
  Number disc = smoothstep(0.99994, 0.99998, cos_sun);
  return sky + vec3(u_cloud.sun_color) * (Number(u_cloud.sky.w) * disc);
}

// Aerial perspective for layer mode: distant clouds fade into the horizon sky with a 30 km scale
// (Beer-Lambert of a clear atmosphere's haze), which also hides their sampling noise at the horizon.
// `cloud` is (radiance, transmittance) from march_clouds; returns the faded pair.
vec4 aerial_perspective(vec4 cloud, Number t_mean, vec3 rd) {
  if (!layer_mode() || cloud.w >= 1.0) return cloud;
  Number haze = 1.0 - exp(-t_mean / 30000.0);
  vec3 sky = sky_radiance(vec3(rd.x, max(rd.y, 0.0), rd.z));
  vec3 faded = mix(vec3(cloud), sky * (1.0 - cloud.w), haze);
  return vec4(faded, cloud.w);
}

// ---------------------------------------------------------------- HDR post

// Tone mapping of exposed linear radiance: 0 Reinhard L/(1+L), 1 ACES filmic (Narkowicz 2015), 2 clamp.
vec3 tone_map(vec3 hdr, Number exposure, int op) {
  vec3 x = max(hdr * exposure, vec3(0.0));
  if (op == 1) return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
  if (op == 2) return clamp(x, 0.0, 1.0);
  return x / (vec3(1.0) + x);
}

Number srgb_encode_channel(Number c) {
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
vec3 srgb_encode(vec3 c) {
  return vec3(srgb_encode_channel(c.x), srgb_encode_channel(c.y), srgb_encode_channel(c.z));
}

// Bloom bright pass on the half-resolution image: what exceeds the threshold.
vec3 bloom_bright(vec3 c, Number threshold) { return max(c - vec3(threshold), vec3(0.0)); }

// Normalised weight of tap i in [-radius, radius] of a Gaussian with the given sigma (in texels).
Number gaussian_weight(int i, int radius, Number sigma) {
  Number sum = 0.0;
  for (int j = -radius; j <= radius; ++j) sum += exp(-Number(j * j) / (2.0 * sigma * sigma));
  return exp(-Number(i * i) / (2.0 * sigma * sigma)) / sum;
}
