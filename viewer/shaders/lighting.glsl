// Lighting of the medium and the ground: Beer-Lambert with the powder term (Hogfeldt 2016, thesis
// 2.5), energy-conserving step integration (S. Hillaire, "Physically Based and Unified Volumetric
// Rendering in Frostbite", SIGGRAPH 2015), the light march toward the sun, cloud shadows on the
// ground. Needs common.glsl, phase.glsl, medium.glsl and `u_cloud`.

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
  bool skip_empty = int(u_cloud.light_mode) == CV_LIGHT_MARCH_SKIP_EMPTY;
  Number s = 0.0;
  Number tau = 0.0;
  for (int i = 0; i < samples; ++i) {
    vec3 q = p + sun * (s + 0.5 * step_len);
    // The same coarse grid also spares the light march its texture reads in empty cells, where
    // the density is exactly 0 (an addition to the thesis, `render.occupancy_light`).
    if (!skip_empty || occupied(q)) tau += cloud_density(q) * u_cloud.sigma_t_per_m * step_len;
    s += step_len;
    step_len *= growth;
  }
  return tau;
}

// Radiance scattered toward the viewer at p per unit sigma_s: sun irradiance * phase *
// Beer(tau) * powder mix + ambient sky radiance.
vec3 inscattered_radiance(vec3 p, Number phase) {
  Number tau = int(u_cloud.light_mode) != CV_LIGHT_OFF ? light_optical_depth(p) : 0.0;
  Number powder = mix(1.0, powder_term(tau, u_cloud.powder_c), u_cloud.powder_strength);
  vec3 sun = sun_color_at(p) * (u_cloud.sun_radiance * phase * beer_lambert(tau) * powder);
  // Isotropic ambient radiance: the phase function integrates to 1, so it scatters as it is.
  vec3 ambient = u_cloud.ambient_color * u_cloud.ambient_scale;
  return sun + ambient;
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
  for (int i = 0; i < samples; ++i) {
    tau += cloud_density(p + sun * (tb.x + (Number(i) + 0.5) * seg));
  }
  return exp(-tau * seg * u_cloud.sigma_t_per_m);
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
  Number shadow = mu > 0.0 ? sun_shadow_transmittance(p) : 0.0;
  vec3 irradiance = sun_color_at(p) * (u_cloud.sun_radiance * mu * shadow)
                  + u_cloud.ambient_color * (u_cloud.ambient_scale * CV_PI);
  return albedo * irradiance / CV_PI;
}
