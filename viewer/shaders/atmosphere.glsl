// Precomputed atmospheric scattering after Bruneton & Neyret (2008) and Bruneton's 2017 reference
// implementation (ebruneton/precomputed_atmospheric_scattering: the formulas and the texture
// parametrisation follow its functions.glsl; this is an independent write-up of them). Written in
// the GLSL subset that C++ also compiles (see march.glsl): the GL precompute passes and the CPU
// reference (src/atmosphere.cpp, double precision) run these same lines.
// Needs constants.glsl, `u_atmo` (AtmosphereParams) and the lookup `transmittance_texel(ivec2)`
// (the transmittance LUT's texel, RGB; GLSL: texelFetch in atmosphere_bindings.glsl).
//
// Geometry: a point at distance r from the planet centre looking along a direction whose cosine
// with the local zenith is mu. All radii in metres.

Number atmo_safe_sqrt(Number a) { return sqrt(max(a, 0.0)); }

// Distance along (r, mu) to the top of the atmosphere (r <= top), and to the ground.
Number distance_to_top_boundary(Number r, Number mu) {
  Number top = u_atmo.top_radius_m;
  Number disc = r * r * (mu * mu - 1.0) + top * top;
  return max(-r * mu + atmo_safe_sqrt(disc), 0.0);
}
Number distance_to_bottom_boundary(Number r, Number mu) {
  Number bottom = u_atmo.bottom_radius_m;
  Number disc = r * r * (mu * mu - 1.0) + bottom * bottom;
  return max(-r * mu - atmo_safe_sqrt(disc), 0.0);
}
bool ray_intersects_ground(Number r, Number mu) {
  Number bottom = u_atmo.bottom_radius_m;
  return mu < 0.0 && r * r * (mu * mu - 1.0) + bottom * bottom >= 0.0;
}

// Density profiles in [0, 1] at altitude h above the ground.
Number rayleigh_density(Number h) { return exp(-max(h, 0.0) / u_atmo.rayleigh_scale_height_m); }
Number mie_density(Number h) { return exp(-max(h, 0.0) / u_atmo.mie_scale_height_m); }
Number ozone_density(Number h) {
  Number rise = (h - u_atmo.ozone_bottom_m) / max(u_atmo.ozone_peak_m - u_atmo.ozone_bottom_m, 1.0);
  Number fall = (u_atmo.ozone_top_m - h) / max(u_atmo.ozone_top_m - u_atmo.ozone_peak_m, 1.0);
  return clamp(h < u_atmo.ozone_peak_m ? rise : fall, 0.0, 1.0);
}
// Extinction coefficient (per metre, RGB) at altitude h: Rayleigh scattering, Mie extinction and
// ozone absorption.
vec3 atmosphere_extinction(Number h) {
  return u_atmo.rayleigh_scattering_per_m * rayleigh_density(h) + u_atmo.mie_extinction_per_m * mie_density(h) +
         u_atmo.ozone_absorption_per_m * ozone_density(h);
}

// Optical depth from (r, mu) to the top of the atmosphere: trapezoidal rule over
// CV_TRANSMITTANCE_SAMPLES intervals of the segment (Bruneton uses the same rule and count).
vec3 optical_depth_to_top(Number r, Number mu) {
  int n = CV_TRANSMITTANCE_SAMPLES;
  Number dx = distance_to_top_boundary(r, mu) / Number(n);
  vec3 sum = vec3(0.0);
  for (int i = 0; i <= n; ++i) {
    Number d = Number(i) * dx;
    Number r_i = sqrt(d * d + 2.0 * r * mu * d + r * r);  // law of cosines
    Number w = (i == 0 || i == n) ? 0.5 : 1.0;
    sum += atmosphere_extinction(r_i - u_atmo.bottom_radius_m) * (w * dx);
  }
  return sum;
}

// Texture coordinates with half-texel margins: x in [0, 1] maps onto the centres of the first and
// last texels, so a lookup never extrapolates past the edge texels.
Number unit_to_texcoord(Number x, int n) { return 0.5 / Number(n) + x * (1.0 - 1.0 / Number(n)); }
Number texcoord_to_unit(Number u, int n) { return (u - 0.5 / Number(n)) / (1.0 - 1.0 / Number(n)); }

// Bruneton's transmittance parametrisation: x_r = rho / H (rho: distance to the horizon from r,
// H: the same from the top) and x_mu the distance to the top mapped between its minimum (straight
// up, top - r) and its maximum (towards the horizon, rho + H). Rays that hit the ground are not in
// the table (their x_mu would exceed 1); callers check ray_intersects_ground first.
vec2 transmittance_uv(Number r, Number mu) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number H = sqrt(top * top - bottom * bottom);
  Number rho = atmo_safe_sqrt(r * r - bottom * bottom);
  Number d = distance_to_top_boundary(r, mu);
  Number d_min = top - r;
  Number d_max = rho + H;
  Number x_mu = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
  Number x_r = rho / H;
  return vec2(unit_to_texcoord(clamp(x_mu, 0.0, 1.0), CV_TRANSMITTANCE_W),
              unit_to_texcoord(clamp(x_r, 0.0, 1.0), CV_TRANSMITTANCE_H));
}
// The inverse: (r, mu) of a texture coordinate (the precompute pass evaluates texel centres).
vec2 transmittance_r_mu(vec2 uv) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number x_mu = texcoord_to_unit(uv.x, CV_TRANSMITTANCE_W);
  Number x_r = texcoord_to_unit(uv.y, CV_TRANSMITTANCE_H);
  Number H = sqrt(top * top - bottom * bottom);
  Number rho = H * x_r;
  Number r = sqrt(rho * rho + bottom * bottom);
  Number d_min = top - r;
  Number d_max = rho + H;
  Number d = d_min + x_mu * (d_max - d_min);
  Number mu = d == 0.0 ? 1.0 : (H * H - rho * rho - d * d) / (2.0 * r * d);
  return vec2(r, clamp(mu, -1.0, 1.0));
}

// The precompute pass: the value of texel `texel` (its centre).
vec3 compute_transmittance_texel(ivec2 texel) {
  vec2 uv = (vec2(texel) + 0.5) / vec2(CV_TRANSMITTANCE_W, CV_TRANSMITTANCE_H);
  vec2 r_mu = transmittance_r_mu(uv);
  return exp(-optical_depth_to_top(r_mu.x, r_mu.y));
}

// The lookup every later pass uses: transmittance from (r, mu) to the top of the atmosphere,
// bilinear between the four nearest texels (by hand, so GL and the CPU reference filter alike).
// Only meaningful for rays that do not hit the ground.
vec3 transmittance_to_top(Number r, Number mu) {
  vec2 p = transmittance_uv(r, mu) * vec2(CV_TRANSMITTANCE_W, CV_TRANSMITTANCE_H) - 0.5;
  ivec2 i0 = ivec2(clamp(floor(p.x), 0.0, Number(CV_TRANSMITTANCE_W - 2)),
                   clamp(floor(p.y), 0.0, Number(CV_TRANSMITTANCE_H - 2)));
  vec2 f = clamp(p - vec2(i0), 0.0, 1.0);
  vec3 a = mix(transmittance_texel(i0), transmittance_texel(i0 + ivec2(1, 0)), f.x);
  vec3 b = mix(transmittance_texel(i0 + ivec2(0, 1)), transmittance_texel(i0 + ivec2(1, 1)), f.x);
  return mix(a, b, f.y);
}

// ------------------------------------------------------------------------------- single scattering
// Transmittance between (r, mu) and the point at distance d along the ray (inside the atmosphere),
// as a ratio of two LUT lookups; rays that hit the ground use the reversed ray, which does not.
vec3 transmittance_along(Number r, Number mu, Number d, bool hits_ground) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
  Number mu_d = clamp((r * mu + d) / r_d, -1.0, 1.0);
  vec3 num = hits_ground ? transmittance_to_top(r_d, -mu_d) : transmittance_to_top(r, mu);
  vec3 den = hits_ground ? transmittance_to_top(r, -mu) : transmittance_to_top(r_d, mu_d);
  return min(num / max(den, vec3(1e-30)), vec3(1.0));
}

// Sunlight reaching radius r with the sun at cosine mu_s from the zenith: the transmittance to the
// top times the visible fraction of the sun's disc above the horizon (a smooth set, zero in the
// Earth's shadow), after Bruneton's GetTransmittanceToSun.
vec3 transmittance_to_sun(Number r, Number mu_s) {
  Number sin_h = u_atmo.bottom_radius_m / r;
  Number cos_h = -atmo_safe_sqrt(1.0 - sin_h * sin_h);
  Number a = u_atmo.sun_angular_radius * sin_h;
  return transmittance_to_top(r, mu_s) * smoothstep(-a, a, mu_s - cos_h);
}

// Phase functions (1/sr): Rayleigh and Cornette-Shanks for Mie.
Number rayleigh_phase(Number nu) { return 3.0 / (16.0 * CV_PI) * (1.0 + nu * nu); }
Number mie_phase(Number g, Number nu) {
  Number k = 3.0 / (8.0 * CV_PI) * (1.0 - g * g) / (2.0 + g * g);
  return k * (1.0 + nu * nu) / pow(max(1.0 + g * g - 2.0 * g * nu, 1e-6), 1.5);
}

// Radiance of the sky seen from altitude `alt` (planet centre straight below, zenith +y) along unit
// `v`, with the sun along unit `s` and `solar` its irradiance at the top of the atmosphere: single
// Rayleigh + Mie scattering ray-marched per pixel (CV_SKY_SAMPLES midpoint samples, each reading
// the transmittance LUT) up to the top, the ground or t_max. `transmittance` receives the view
// ray's transmittance over that segment (0 when it ends on the ground), `t_end` its length from the
// camera (CV_NO_HIT when the ray misses the atmosphere) and `ground` the sunlit ground radiance
// there (albedo / pi * direct sun; 0 when the ray does not end on the ground).
vec3 atmosphere_scattering(Number alt, vec3 v, vec3 s, vec3 solar, Number t_max, OUT(vec3) transmittance,
                           OUT(Number) t_end, OUT(vec3) ground) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  transmittance = vec3(1.0);
  ground = vec3(0.0);
  t_end = CV_NO_HIT;
  Number r = bottom + clamp(alt, 0.0, 1e9);
  Number mu = clamp(v.y, -1.0, 1.0);
  Number mu_s = clamp(s.y, -1.0, 1.0);
  Number nu = clamp(dot(v, s), -1.0, 1.0);
  Number t0 = 0.0;
  if (r > top) {  // from space: start where the ray enters the atmosphere
    Number rmu = r * mu;
    Number disc = rmu * rmu - r * r + top * top;
    if (disc < 0.0 || rmu > 0.0) return vec3(0.0);
    t0 = -rmu - sqrt(disc);
    mu = clamp((r * mu + t0) / top, -1.0, 1.0);
    mu_s = clamp((r * mu_s + t0 * nu) / top, -1.0, 1.0);
    r = top;
  }
  bool hits_ground = ray_intersects_ground(r, mu);
  Number d_atmo = hits_ground ? distance_to_bottom_boundary(r, mu) : distance_to_top_boundary(r, mu);
  Number d_end = clamp(t_max - t0, 0.0, d_atmo);
  int n = CV_SKY_SAMPLES;
  Number dx = d_end / Number(n);
  vec3 rayleigh = vec3(0.0);
  vec3 mie = vec3(0.0);
  for (int i = 0; i < n; ++i) {
    Number d = (Number(i) + 0.5) * dx;
    Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
    Number mu_s_d = clamp((r * mu_s + d * nu) / r_d, -1.0, 1.0);
    vec3 t = transmittance_along(r, mu, d, hits_ground) * transmittance_to_sun(r_d, mu_s_d);
    rayleigh += t * rayleigh_density(r_d - bottom);
    mie += t * mie_density(r_d - bottom);
  }
  t_end = t0 + d_end;
  transmittance = transmittance_along(r, mu, d_end, hits_ground);
  if (hits_ground && d_end >= d_atmo) {
    Number mu_s_g = clamp((r * mu_s + d_end * nu) / bottom, -1.0, 1.0);
    ground = u_atmo.ground_albedo / CV_PI * solar * transmittance_to_sun(bottom, mu_s_g) * max(mu_s_g, 0.0);
  }
  return solar * dx * (rayleigh * u_atmo.rayleigh_scattering_per_m * rayleigh_phase(nu) +
                       mie * u_atmo.mie_scattering_per_m * mie_phase(u_atmo.mie_g, nu));
}

// The sun's disc along unit `v` (radiance relative to `disc_radiance`): limb darkening
// 1 - 0.6 (1 - cos theta) across the disc (theta: the angle at the sun's surface), an anti-aliased
// rim, and the transmittance to the top (0 where the line of sight hits the ground: a partial set).
vec3 atmosphere_sun_disc(Number alt, vec3 v, vec3 s, vec3 disc_radiance) {
  Number r = u_atmo.bottom_radius_m + clamp(alt, 0.0, 1e9);
  Number alpha = u_atmo.sun_angular_radius;
  Number angle = acos(clamp(dot(v, s), -1.0, 1.0));
  if (angle >= alpha * 1.2) return vec3(0.0);
  Number x = min(angle / alpha, 1.0);
  Number limb = 1.0 - 0.6 * (1.0 - sqrt(max(1.0 - x * x, 0.0)));
  Number rim = 1.0 - smoothstep(0.9, 1.2, angle / alpha);
  Number mu = clamp(v.y, -1.0, 1.0);
  if (ray_intersects_ground(r, mu)) return vec3(0.0);
  Number top = u_atmo.top_radius_m;
  if (r > top) {  // from space: through the atmosphere from where the line of sight enters it
    Number rmu = r * mu;
    Number disc = rmu * rmu - r * r + top * top;
    if (disc < 0.0 || rmu > 0.0) return disc_radiance * (limb * rim);
    mu = clamp(-sqrt(disc) / top, -1.0, 1.0);  // (r mu + t0) / top at the entry t0 = -r mu - sqrt(disc)
    r = top;
  }
  return disc_radiance * transmittance_to_top(r, mu) * (limb * rim);
}
