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
