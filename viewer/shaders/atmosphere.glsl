// Precomputed atmospheric scattering after Bruneton & Neyret (2008) and Bruneton's 2017 reference
// implementation (ebruneton/precomputed_atmospheric_scattering: the formulas and the texture
// parametrisation follow its functions.glsl; this is an independent write-up of them). Written in
// the GLSL subset that C++ also compiles (see march.glsl): the GL precompute passes and the CPU
// reference (src/atmosphere.cpp, double precision) run these same lines.
// Needs constants.glsl, `u_atmo` (AtmosphereParams) and the lookups `transmittance_texel(ivec2)`,
// `multiple_scattering_texel(ivec2)` and `irradiance_texel(int)` (the LUTs' texels, RGB; GLSL:
// texelFetch in atmosphere_bindings.glsl).
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
vec3 transmittance_bilinear(vec2 uv) {
  vec2 p = uv * vec2(CV_TRANSMITTANCE_W, CV_TRANSMITTANCE_H) - 0.5;
  ivec2 i0 = ivec2(clamp(floor(p.x), 0.0, Number(CV_TRANSMITTANCE_W - 2)),
                   clamp(floor(p.y), 0.0, Number(CV_TRANSMITTANCE_H - 2)));
  vec2 f = clamp(p - vec2(i0), 0.0, 1.0);
  vec3 a = mix(transmittance_texel(i0), transmittance_texel(i0 + ivec2(1, 0)), f.x);
  vec3 b = mix(transmittance_texel(i0 + ivec2(0, 1)), transmittance_texel(i0 + ivec2(1, 1)), f.x);
  return mix(a, b, f.y);
}
vec3 transmittance_to_top(Number r, Number mu) { return transmittance_bilinear(transmittance_uv(r, mu)); }

// ------------------------------------------------------------------------------- single scattering
// Transmittance between (r, mu) and the point at distance d along the ray (inside the atmosphere),
// as a ratio of two LUT lookups; rays that hit the ground use the reversed ray, which does not.
// The ray is chosen before the two lookups, not between four: llvmpipe evaluates both sides of a
// per-pixel choice.
vec3 transmittance_along(Number r, Number mu, Number d, bool hits_ground) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
  Number mu_d = clamp((r * mu + d) / r_d, -1.0, 1.0);
  vec3 num = transmittance_to_top(hits_ground ? r_d : r, hits_ground ? -mu_d : mu);
  vec3 den = transmittance_to_top(hits_ground ? r : r_d, hits_ground ? -mu : mu_d);
  return min(num / max(den, vec3(1e-30)), vec3(1.0));
}

// Sunlight reaching radius r with the sun at cosine mu_s from the zenith: the transmittance to the
// top times the visible fraction of the sun's disc above the horizon (a smooth set, zero in the
// Earth's shadow), after Bruneton's GetTransmittanceToSun.
Number sun_disc_visible(Number r, Number mu_s) {
  Number sin_h = u_atmo.bottom_radius_m / r;
  Number cos_h = -atmo_safe_sqrt(1.0 - sin_h * sin_h);
  Number a = u_atmo.sun_angular_radius * sin_h;
  return smoothstep(-a, a, mu_s - cos_h);
}
vec3 transmittance_to_sun(Number r, Number mu_s) { return transmittance_to_top(r, mu_s) * sun_disc_visible(r, mu_s); }

// Phase functions (1/sr): Rayleigh and Cornette-Shanks for Mie.
Number rayleigh_phase(Number nu) { return 3.0 / (16.0 * CV_PI) * (1.0 + nu * nu); }
Number mie_phase(Number g, Number nu) {
  Number k = 3.0 / (8.0 * CV_PI) * (1.0 - g * g) / (2.0 + g * g);
  return k * (1.0 + nu * nu) / pow(max(1.0 + g * g - 2.0 * g * nu, 1e-6), 1.5);
}

// ----------------------------------------------------------------------------- multiple scattering
// After Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering Technique" (EGSR
// 2020): the light scattered two or more times reaching a point is nearly isotropic and depends
// mostly on the altitude and the sun's zenith angle, so one small LUT Psi_ms(r, mu_s) holds it.
// At each texel, with unit sun irradiance at the top of the atmosphere and isotropic phase for the
// orders it gathers:
//   L2 = 1/(4 pi) int_sphere L'(w) dw,  L'(w) = int_0^d T(x, y) sigma_s(y) T_sun(y) / (4 pi) dt
//                                              + [ground] T(x, g) albedo / pi T_sun(g) max(mu_s(g), 0)
//   f  = 1/(4 pi) int_sphere int_0^d T(x, y) sigma_s(y) dt dw   (the fraction a point re-scatters)
// and the orders 2..N sum to Psi_ms = L2 (1 + f + ... + f^(N-2)) (Hillaire's L2 / (1 - f) as N grows).
// A sample of the view march then adds sigma_s(y) Psi_ms(y) to its single scattering.

// Scattering coefficient (Rayleigh + Mie, per metre, RGB) at altitude h.
vec3 atmosphere_scattering_coefficient(Number h) {
  return u_atmo.rayleigh_scattering_per_m * rayleigh_density(h) + u_atmo.mie_scattering_per_m * mie_density(h);
}

// LUT coordinates onto texel centres (half-texel margins): x = 1/2 + sign(mu_s) sqrt|mu_s| / 2,
// which puts texels where Psi changes fastest, the sun near the horizon (the worst error between
// texels at 32^2: 6.5% linear in mu_s, 4.7% so; docs/sky.md), and y = altitude, linear.
vec2 multiple_scattering_uv(Number r, Number mu_s) {
  Number x_mu_s = clamp(0.5 + 0.5 * sign(mu_s) * sqrt(abs(mu_s)), 0.0, 1.0);
  Number x_r = clamp((r - u_atmo.bottom_radius_m) / (u_atmo.top_radius_m - u_atmo.bottom_radius_m), 0.0, 1.0);
  return vec2(unit_to_texcoord(x_mu_s, CV_MS_LUT_SIZE), unit_to_texcoord(x_r, CV_MS_LUT_SIZE));
}

// The precompute pass: Psi_ms at the centre of texel `texel`. Reads the transmittance LUT.
vec3 compute_multiple_scattering_texel(ivec2 texel) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number x_mu_s = texcoord_to_unit((Number(texel.x) + 0.5) / Number(CV_MS_LUT_SIZE), CV_MS_LUT_SIZE);
  Number x_r = texcoord_to_unit((Number(texel.y) + 0.5) / Number(CV_MS_LUT_SIZE), CV_MS_LUT_SIZE);
  Number y_mu_s = 2.0 * x_mu_s - 1.0;
  Number mu_s = clamp(sign(y_mu_s) * y_mu_s * y_mu_s, -1.0, 1.0);
  Number r = bottom + x_r * (top - bottom);
  vec3 s = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), mu_s, 0.0);  // the sun, zenith +y
  // The sphere split at the horizon (cosine mu_h): CV_MS_SKY_BANDS bands over the sky and
  // CV_MS_GROUND_BANDS over the ground at the midpoints of u, with mu = mu_h + (1 - mu_h) u^3 (and
  // mu_h - (1 + mu_h) u^3 below), which gathers bands at the horizon where the grazing rays carry
  // most light; CV_MS_SECTORS sectors of phi over [0, pi], counted twice (the light is symmetric
  // about the sun's vertical plane). Within 1.7% of a converged integral with 8 + 4 bands x 8
  // sectors (tests/test_atmosphere.cpp), against 5-60% for 8 x 8 equal-area strata.
  Number mu_h = -atmo_safe_sqrt(1.0 - (bottom / r) * (bottom / r));
  vec3 l2 = vec3(0.0);
  vec3 f = vec3(0.0);
  for (int part = 0; part < 2; ++part) {
    int bands = part == 0 ? CV_MS_SKY_BANDS : CV_MS_GROUND_BANDS;
    Number span = part == 0 ? 1.0 - mu_h : 1.0 + mu_h;
    for (int i = 0; i < bands; ++i) {
      Number u = (Number(i) + 0.5) / Number(bands);
      Number mu = clamp(part == 0 ? mu_h + span * u * u * u : mu_h - span * u * u * u, -1.0, 1.0);
      Number weight = span * 3.0 * u * u / Number(bands) * (2.0 * CV_PI / Number(CV_MS_SECTORS));  // d(mu) d(phi)
      Number sin_t = sqrt(max(1.0 - mu * mu, 0.0));
      for (int j = 0; j < CV_MS_SECTORS; ++j) {
        Number phi = CV_PI * (Number(j) + 0.5) / Number(CV_MS_SECTORS);
        vec3 v = vec3(sin_t * cos(phi), mu, sin_t * sin(phi));
        Number nu = dot(v, s);
        bool hits_ground = part == 1 && ray_intersects_ground(r, mu);
        Number d_end = hits_ground ? distance_to_bottom_boundary(r, mu) : distance_to_top_boundary(r, mu);
        Number dx = d_end / Number(CV_MS_STEPS);
        vec3 lum = vec3(0.0);
        vec3 transfer = vec3(0.0);
        for (int k = 0; k < CV_MS_STEPS; ++k) {
          Number d = (Number(k) + 0.5) * dx;
          Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
          Number mu_s_d = clamp((r * mu_s + d * nu) / r_d, -1.0, 1.0);
          vec3 t = transmittance_along(r, mu, d, hits_ground);
          vec3 sigma_s = atmosphere_scattering_coefficient(r_d - bottom);
          lum += t * sigma_s * transmittance_to_sun(r_d, mu_s_d);
          transfer += t * sigma_s;
        }
        lum *= dx / (4.0 * CV_PI);
        if (hits_ground) {
          Number mu_s_g = clamp((r * mu_s + d_end * nu) / bottom, -1.0, 1.0);
          lum += transmittance_along(r, mu, d_end, true) * u_atmo.ground_albedo / CV_PI *
                 transmittance_to_sun(bottom, mu_s_g) * max(mu_s_g, 0.0);
        }
        l2 += lum * weight;
        f += transfer * (dx * weight);
      }
    }
  }
  l2 /= 4.0 * CV_PI;
  f /= 4.0 * CV_PI;
  // Orders 2..N: L2 (1 + f + ... + f^(N-2)).
  vec3 series = vec3(0.0);
  vec3 term = vec3(1.0);
  int orders = int(u_atmo.scattering_orders + 0.5);
  for (int o = 2; o <= orders; ++o) {
    series += term;
    term *= f;
  }
  return l2 * series;
}

// Psi_ms(r, mu_s) for unit solar irradiance, bilinear between the four nearest texels (by hand).
vec3 multiple_scattering_at(Number r, Number mu_s) {
  vec2 p = multiple_scattering_uv(r, mu_s) * Number(CV_MS_LUT_SIZE) - 0.5;
  ivec2 i0 = ivec2(clamp(floor(p.x), 0.0, Number(CV_MS_LUT_SIZE - 2)), clamp(floor(p.y), 0.0, Number(CV_MS_LUT_SIZE - 2)));
  vec2 w = clamp(p - vec2(i0), 0.0, 1.0);
  vec3 a = mix(multiple_scattering_texel(i0), multiple_scattering_texel(i0 + ivec2(1, 0)), w.x);
  vec3 b = mix(multiple_scattering_texel(i0 + ivec2(0, 1)), multiple_scattering_texel(i0 + ivec2(1, 1)), w.x);
  return mix(a, b, w.y);
}

// The ground irradiance LUT's lookup (compute_irradiance_texel below fills it): linear between
// the two nearest texels.
Number irradiance_u(Number mu_s) { return unit_to_texcoord(clamp(mu_s * 0.5 + 0.5, 0.0, 1.0), CV_IRRADIANCE_W); }
// `orders`: the same lookup in the orders passes' irradiance of the last order (orders_irradiance_texel).
vec3 irradiance_lookup(bool orders, Number mu_s) {
  Number p = irradiance_u(mu_s) * Number(CV_IRRADIANCE_W) - 0.5;
  int i0 = int(clamp(floor(p), 0.0, Number(CV_IRRADIANCE_W - 2)));
  Number w = clamp(p - Number(i0), 0.0, 1.0);
  if (orders) return mix(orders_irradiance_texel(i0), orders_irradiance_texel(i0 + 1), w);
  return mix(irradiance_texel(i0), irradiance_texel(i0 + 1), w);
}
vec3 ground_sky_irradiance(Number mu_s) { return irradiance_lookup(false, mu_s); }

// The quadrature of both ground irradiance LUTs (compute_irradiance_texel, and the density
// orders' compute_orders_irradiance_texel): texel `texel`'s sun cosine; the direction (zenith +y)
// of band i of cos(theta) and sector k of phi in [0, pi] (counted twice: the light is symmetric
// about the sun's vertical plane, the sun in the x-y plane); each direction's weight d(mu) d(phi)
// times its cosine v.y.
Number irradiance_texel_mu_s(int texel) {
  Number x = texcoord_to_unit((Number(texel) + 0.5) / Number(CV_IRRADIANCE_W), CV_IRRADIANCE_W);
  return clamp(2.0 * x - 1.0, -1.0, 1.0);
}
vec3 irradiance_direction(int i, int k) {
  Number mu = (Number(i) + 0.5) / Number(CV_IRRADIANCE_BANDS);
  Number sin_t = sqrt(max(1.0 - mu * mu, 0.0));
  Number phi = CV_PI * (Number(k) + 0.5) / Number(CV_IRRADIANCE_SECTORS);
  return vec3(sin_t * cos(phi), mu, sin_t * sin(phi));
}
Number irradiance_weight() { return 2.0 * CV_PI / Number(CV_IRRADIANCE_BANDS * CV_IRRADIANCE_SECTORS); }

// The single-scattering integrals along (r, mu) over [0, d_end] with the sun at mu_s and nu = v.s,
// for unit solar irradiance, before the phase functions and the scattering coefficients: the sums
// of T(view) T(sun) rho_R and of T(view) T(sun) rho_M, and (with `multiple`) of T(view) sigma_s
// Psi_ms, over CV_SKY_SAMPLES samples at d = d_end x^2 (x: the midpoints of equal intervals), each
// weighted 2 x: dense near the start, where the air is densest along most rays. Times
// d_end / CV_SKY_SAMPLES they are the integrals. The per-pixel march and the scattering LUT's
// texels both use it; `hits_ground` says which boundary ends the ray.
void scattering_sums(Number r, Number mu, Number mu_s, Number nu, Number d_end, bool hits_ground, bool multiple,
                     OUT(vec3) rayleigh, OUT(vec3) mie, OUT(vec3) ms) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  rayleigh = vec3(0.0);
  mie = vec3(0.0);
  ms = vec3(0.0);
  int n = CV_SKY_SAMPLES;
  for (int i = 0; i < n; ++i) {
    Number x = (Number(i) + 0.5) / Number(n);
    Number d = d_end * x * x;
    Number w = 2.0 * x;
    Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
    Number mu_s_d = clamp((r * mu_s + d * nu) / r_d, -1.0, 1.0);
    vec3 t_view = transmittance_along(r, mu, d, hits_ground);
    vec3 t = t_view * transmittance_to_sun(r_d, mu_s_d) * w;
    rayleigh += t * rayleigh_density(r_d - bottom);
    mie += t * mie_density(r_d - bottom);
    if (multiple) ms += t_view * w * atmosphere_scattering_coefficient(r_d - bottom) * multiple_scattering_at(r_d, mu_s_d);
  }
}

// ------------------------------------------------------------------------ the 4D scattering LUT
// Bruneton & Neyret's table of the sky's scattered light S(r, mu, mu_s, nu) for unit solar
// irradiance, with Bruneton's 2017 parametrisation (functions.glsl,
// GetScatteringTextureUvwzFromRMuMuSNu): u_r = rho / H; u_mu the distance to the boundary the ray
// ends on, mapped between its minimum and maximum, the rays that hit the ground in the lower half
// of the mu axis and the others in the upper half, each half with its own half-texel margins (so a
// lookup never mixes the two); u_mu_s from the distance to the top from the ground towards the sun,
// mu_s_min and below at 0; u_nu = (nu + 1) / 2, linear. The 4D table is packed as
// CV_SCATTERING_NU slices of CV_SCATTERING_MU_S texels side by side along x. Three RGB parts: the
// single Rayleigh and the single Mie scattering, each before its phase function (Bruneton's
// "scattering" and "single_mie_scattering" textures), and the orders 2..N (from the multiple-
// scattering LUT, nearly isotropic). Bruneton folds the last into the first, divided by the
// Rayleigh phase; interpolated linearly in nu over 8 slices, 1 / (1 + nu^2) is then 2% off
// between slices, so here it keeps its own part.

// (u_nu, u_mu_s, u_mu, u_r) in [0, 1] of (r, mu, mu_s, nu) in a table of n = (mu_s, mu, r) texels
// per nu slice (the 4D LUT's, or the smaller orders table's); hits_ground: the ray (r, mu) ends on
// the ground.
vec4 lut4d_uvwz(Number r, Number mu, Number mu_s, Number nu, bool hits_ground, ivec3 n) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number H = sqrt(top * top - bottom * bottom);
  Number rho = atmo_safe_sqrt(r * r - bottom * bottom);
  Number u_r = unit_to_texcoord(clamp(rho / H, 0.0, 1.0), n.z);
  Number r_mu = r * mu;
  Number disc = r_mu * r_mu - r * r + bottom * bottom;
  Number u_mu = 0.0;
  if (hits_ground) {
    Number d = -r_mu - atmo_safe_sqrt(disc);
    Number d_min = r - bottom;
    Number d_max = rho;
    Number x = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
    u_mu = 0.5 - 0.5 * unit_to_texcoord(clamp(x, 0.0, 1.0), n.y / 2);
  } else {
    Number d = -r_mu + atmo_safe_sqrt(disc + H * H);
    Number d_min = top - r;
    Number d_max = rho + H;
    Number x = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
    u_mu = 0.5 + 0.5 * unit_to_texcoord(clamp(x, 0.0, 1.0), n.y / 2);
  }
  Number d_s = distance_to_top_boundary(bottom, mu_s);
  Number d_min_s = top - bottom;
  Number d_max_s = H;
  Number a = (d_s - d_min_s) / (d_max_s - d_min_s);
  Number A = (distance_to_top_boundary(bottom, CV_SCATTERING_MU_S_MIN) - d_min_s) / (d_max_s - d_min_s);
  Number u_mu_s = unit_to_texcoord(clamp(max(1.0 - a / A, 0.0) / (1.0 + a), 0.0, 1.0), n.x);
  return vec4(clamp((nu + 1.0) / 2.0, 0.0, 1.0), u_mu_s, u_mu, u_r);
}
ivec3 scattering_dims() { return ivec3(CV_SCATTERING_MU_S, CV_SCATTERING_MU, CV_SCATTERING_R); }
ivec3 orders_dims() { return ivec3(CV_ORDERS_MU_S, CV_ORDERS_MU, CV_ORDERS_R); }
vec4 scattering_uvwz(Number r, Number mu, Number mu_s, Number nu, bool hits_ground) {
  return lut4d_uvwz(r, mu, mu_s, nu, hits_ground, scattering_dims());
}

// The inverse at the centre of texel `texel` (x = nu slice * CV_SCATTERING_MU_S + mu_s index):
// (r, mu, mu_s, nu) and whether the ray hits the ground (the half of the mu axis it is in). A nu
// slice sits at u_nu = slice / (CV_SCATTERING_NU - 1), so the first and last slices are nu = -1
// and 1; nu is then clamped to what (mu, mu_s) allow.
void lut4d_texel_geometry(ivec3 texel, ivec3 n, OUT(Number) r, OUT(Number) mu, OUT(Number) mu_s, OUT(Number) nu,
                          OUT(bool) hits_ground) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  int slice = texel.x / n.x;
  int i_mu_s = texel.x - slice * n.x;
  Number u_nu = Number(slice) / Number(CV_SCATTERING_NU - 1);
  Number u_mu_s = (Number(i_mu_s) + 0.5) / Number(n.x);
  Number u_mu = (Number(texel.y) + 0.5) / Number(n.y);
  Number u_r = (Number(texel.z) + 0.5) / Number(n.z);
  Number H = sqrt(top * top - bottom * bottom);
  Number rho = H * texcoord_to_unit(u_r, n.z);
  r = sqrt(rho * rho + bottom * bottom);
  hits_ground = u_mu < 0.5;
  if (hits_ground) {
    Number d_min = r - bottom;
    Number d_max = rho;
    Number d = d_min + (d_max - d_min) * texcoord_to_unit(1.0 - 2.0 * u_mu, n.y / 2);
    mu = d == 0.0 ? -1.0 : clamp(-(rho * rho + d * d) / (2.0 * r * d), -1.0, 1.0);
  } else {
    Number d_min = top - r;
    Number d_max = rho + H;
    Number d = d_min + (d_max - d_min) * texcoord_to_unit(2.0 * u_mu - 1.0, n.y / 2);
    mu = d == 0.0 ? 1.0 : clamp((H * H - rho * rho - d * d) / (2.0 * r * d), -1.0, 1.0);
  }
  Number x_mu_s = texcoord_to_unit(u_mu_s, n.x);
  Number d_min_s = top - bottom;
  Number d_max_s = H;
  Number A = (distance_to_top_boundary(bottom, CV_SCATTERING_MU_S_MIN) - d_min_s) / (d_max_s - d_min_s);
  Number a = (A - x_mu_s * A) / (1.0 + x_mu_s * A);
  Number d_s = d_min_s + min(a, A) * (d_max_s - d_min_s);
  mu_s = d_s == 0.0 ? 1.0 : clamp((H * H - d_s * d_s) / (2.0 * bottom * d_s), -1.0, 1.0);
  Number spread = atmo_safe_sqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s));
  nu = clamp(2.0 * u_nu - 1.0, mu * mu_s - spread, mu * mu_s + spread);
}
void scattering_texel_geometry(ivec3 texel, OUT(Number) r, OUT(Number) mu, OUT(Number) mu_s, OUT(Number) nu,
                               OUT(bool) hits_ground) {
  lut4d_texel_geometry(texel, scattering_dims(), r, mu, mu_s, nu, hits_ground);
}

// One part of the table at (u_mu_s, u_mu, u_r) in nu slice `slice`: trilinear between the eight
// nearest texel centres, by hand (GL and the CPU reference filter alike); the mu axis never
// crosses the middle (the two halves' margins keep u_mu within its own half's texel centres).
// Parts 0..2: the 4D LUT's (scattering_dims); 10..15: the orders table's parts 0..5 (orders_dims).
vec3 lut4d_slice(int part, int slice, vec3 uvw, ivec3 n) {
  vec3 p = uvw * vec3(n) - 0.5;
  int half_mu = n.y / 2;
  int lo_mu = p.y < Number(half_mu) - 0.5 ? 0 : half_mu;
  ivec3 i0 = ivec3(clamp(floor(p.x), 0.0, Number(n.x - 2)),
                   clamp(floor(p.y), Number(lo_mu), Number(lo_mu + half_mu - 2)),
                   clamp(floor(p.z), 0.0, Number(n.z - 2)));
  vec3 f = clamp(p - vec3(i0), 0.0, 1.0);
  vec3 acc = vec3(0.0);
  for (int k = 0; k < 8; ++k) {
    ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    ivec3 t = i0 + o;
    t.x += slice * n.x;
    Number w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y) * (o.z == 1 ? f.z : 1.0 - f.z);
    acc += w * (part >= 10   ? orders_texel(part - 10, t)
                : part == 0 ? scattering_texel(t)
                : part == 1 ? single_mie_texel(t)
                            : scattering_multiple_texel(t));
  }
  return acc;
}
vec3 scattering_slice(int part, int slice, vec3 uvw) { return lut4d_slice(part, slice, uvw, scattering_dims()); }

// One part of the orders table (0..5, orders_texel) at (r, mu, mu_s, nu): linear between the two
// nearest nu slices, as scattering_lookup.
vec3 orders_lookup(int part, Number r, Number mu, Number mu_s, Number nu, bool hits_ground) {
  ivec3 n = orders_dims();
  vec4 uvwz = lut4d_uvwz(r, mu, mu_s, nu, hits_ground, n);
  Number x = uvwz.x * Number(CV_SCATTERING_NU - 1);
  int slice = int(clamp(floor(x), 0.0, Number(CV_SCATTERING_NU - 2)));
  Number w = clamp(x - Number(slice), 0.0, 1.0);
  vec3 uvw = vec3(uvwz.y, uvwz.z, uvwz.w);
  return mix(lut4d_slice(10 + part, slice, uvw, n), lut4d_slice(10 + part, slice + 1, uvw, n), w);
}

// The single-scattering parts of the texel at (r, mu, mu_s, nu) (ray to the boundary its half of
// the mu axis names), and with `multiple` the Psi_ms orders along it, from the integrals of the
// per-pixel march (scattering_sums).
void lut4d_single(Number r, Number mu, Number mu_s, Number nu, bool hits_ground, bool multiple, OUT(vec3) rayleigh,
                  OUT(vec3) mie, OUT(vec3) ms) {
  Number d_end = hits_ground ? distance_to_bottom_boundary(r, mu) : distance_to_top_boundary(r, mu);
  vec3 sum_r = vec3(0.0);
  vec3 sum_m = vec3(0.0);
  vec3 sum_ms = vec3(0.0);
  scattering_sums(r, mu, mu_s, nu, d_end, hits_ground, multiple, sum_r, sum_m, sum_ms);
  Number dx = d_end / Number(CV_SKY_SAMPLES);
  rayleigh = dx * sum_r * u_atmo.rayleigh_scattering_per_m;
  mie = dx * sum_m * u_atmo.mie_scattering_per_m;
  ms = dx * sum_ms;
}

// ------------------------------------------- orders 2..N from scattering densities (Bruneton 2008)
// atmosphere.density_orders: Bruneton's own multiple scattering, in the orders table (orders_dims,
// the 4D LUT's parametrisation at a smaller size). For order n = 2..N, with unit solar irradiance:
//  - the density J_n(r, mu, mu_s, nu) = int_sphere L_{n-1}(w_i) (sigma_R P_R(w.w_i) + sigma_M P_M(w.w_i)) dw_i,
//    L_{n-1} the light of order n-1 arriving from w_i (order 1: the single parts with their phase
//    functions; then the last order's light), plus for w_i that hit the ground the ground's
//    reflection, T albedo / pi E_{n-2} (E_0 the direct sun, then the last order's irradiance);
//  - the ground irradiance E_{n-1}(mu_s) of the light of order n-1 (for J_{n+1});
//  - the light L_n = int_0^d T(x, y) J_n(y) dt along the texel's ray; the table's sum adds it.
// Unlike Psi_ms (isotropic orders, Hillaire 2020) each order keeps its angular shape.

// The single parts (before their phase functions) at a texel of the orders table.
void compute_orders_single_texel(ivec3 texel, OUT(vec3) rayleigh, OUT(vec3) mie) {
  Number r = 0.0;
  Number mu = 0.0;
  Number mu_s = 0.0;
  Number nu = 0.0;
  bool hits_ground = false;
  lut4d_texel_geometry(texel, orders_dims(), r, mu, mu_s, nu, hits_ground);
  vec3 ms = vec3(0.0);
  lut4d_single(r, mu, mu_s, nu, hits_ground, false, rayleigh, mie, ms);
}

// Light of order `order` (1: single scattering; more: the last order's, orders part 2) arriving at
// radius r from the direction (mu, nu = w.s) with the sun at mu_s, for unit solar irradiance.
vec3 orders_incident(int order, Number r, Number mu, Number mu_s, Number nu) {
  bool g = ray_intersects_ground(r, mu);
  if (order > 1) return orders_lookup(2, r, mu, mu_s, nu, g);
  return orders_lookup(0, r, mu, mu_s, nu, g) * rayleigh_phase(nu) +
         orders_lookup(1, r, mu, mu_s, nu, g) * mie_phase(u_atmo.mie_g, nu);
}

// Irradiance on the ground of order `order` at the sun's cosine mu_s: 0 the direct sun, more the
// orders passes' irradiance texture (compute_orders_irradiance_texel).
vec3 orders_ground_irradiance(int order, Number mu_s) {
  if (order == 0) return transmittance_to_sun(u_atmo.bottom_radius_m, mu_s) * max(mu_s, 0.0);
  return irradiance_lookup(true, mu_s);
}

// J_order at a texel of the orders table, as its angular integrals A_R and A_M (J = sigma_R A_R +
// sigma_M A_M: the scattering coefficients' steep altitude profiles stay out of the table and its
// interpolation; the Mie profile falls 2.4x between the table's first altitudes). CV_DENSITY_THETA bands of theta x 2 CV_DENSITY_THETA
// sectors of phi (midpoints; Bruneton's ComputeScatteringDensity), zenith +y, the view in the x-y
// plane. Within a band (one mu of the incoming light) the table's texels are the same for every
// phi but for the nu slice, so each band reads the 8 slices once and each phi mixes two of them.
void compute_density_texel(ivec3 texel, int order, OUT(vec3) density_r, OUT(vec3) density_m) {
  Number r = 0.0;
  Number mu = 0.0;
  Number mu_s = 0.0;
  Number nu = 0.0;
  bool hits_ground = false;
  ivec3 n = orders_dims();
  lut4d_texel_geometry(texel, n, r, mu, mu_s, nu, hits_ground);
  Number sin_mu = atmo_safe_sqrt(1.0 - mu * mu);
  vec3 omega = vec3(sin_mu, mu, 0.0);
  Number sun_x = sin_mu > 1e-9 ? clamp((nu - mu * mu_s) / sin_mu, -1.0, 1.0) : 0.0;
  vec3 omega_s = vec3(sun_x, mu_s, atmo_safe_sqrt(1.0 - sun_x * sun_x - mu_s * mu_s));
  Number dphi = CV_PI / Number(CV_DENSITY_THETA);
  Number mu_h = -atmo_safe_sqrt(1.0 - (u_atmo.bottom_radius_m / r) * (u_atmo.bottom_radius_m / r));
  vec3 slice_a[CV_SCATTERING_NU];  // order 2: single Rayleigh; later: the last order's light
  vec3 slice_b[CV_SCATTERING_NU];  // order 2: single Mie
  // Accumulated apart: [incoming light but the Mie part of order 1] and [that Mie part], each
  // times the Rayleigh and the Mie phase toward the view; and each phase lobe's own quadrature
  // sum, toward the view (w_r, w_m) and around the sun (w_s).
  vec3 j_ra = vec3(0.0);
  vec3 j_rb = vec3(0.0);
  vec3 j_ma = vec3(0.0);
  vec3 j_mb = vec3(0.0);
  Number w_r = 0.0;
  Number w_m = 0.0;
  Number w_s = 0.0;
  for (int l = 0; l < CV_DENSITY_THETA; ++l) {
    // Bands gathered at the horizon (cosine mu_h), where the light changes fastest (bright grazing
    // sky over the dark ground): 10 over the sky and 6 over the ground at the midpoints of u,
    // mu = mu_h + (1 - mu_h) u^3 above and mu_h - (1 + mu_h) u^3 below (compute_multiple_scattering_texel's).
    int sky_bands = CV_DENSITY_THETA * 5 / 8;
    bool below = l >= sky_bands;
    int bands = below ? CV_DENSITY_THETA - sky_bands : sky_bands;
    Number u = (Number(below ? l - sky_bands : l) + 0.5) / Number(bands);
    Number span = below ? 1.0 + mu_h : 1.0 - mu_h;
    Number ct = clamp(below ? mu_h - span * u * u * u : mu_h + span * u * u * u, -1.0, 1.0);
    Number st = atmo_safe_sqrt(1.0 - ct * ct);
    Number dmu = span * 3.0 * u * u / Number(bands);  // d(mu) of the band: d(omega) = d(mu) d(phi)
    bool ground = below && ray_intersects_ground(r, ct);
    vec4 uvwz = lut4d_uvwz(r, ct, mu_s, 0.0, ground, n);
    vec3 uvw = vec3(uvwz.y, uvwz.z, uvwz.w);
    for (int k = 0; k < CV_SCATTERING_NU; ++k) {
      slice_a[k] = lut4d_slice(order == 2 ? 10 : 12, k, uvw, n);
      slice_b[k] = order == 2 ? lut4d_slice(11, k, uvw, n) : vec3(0.0);
    }
    Number d_ground = 0.0;
    vec3 t_ground = vec3(0.0);
    if (ground) {
      d_ground = distance_to_bottom_boundary(r, ct);
      t_ground = transmittance_along(r, ct, d_ground, true);
    }
    for (int m = 0; m < 2 * CV_DENSITY_THETA; ++m) {
      Number phi = (Number(m) + 0.5) * dphi;
      vec3 omega_i = vec3(cos(phi) * st, ct, sin(phi) * st);
      Number nu_i = clamp(dot(omega_s, omega_i), -1.0, 1.0);
      Number x = (nu_i + 1.0) / 2.0 * Number(CV_SCATTERING_NU - 1);
      int k0 = int(clamp(floor(x), 0.0, Number(CV_SCATTERING_NU - 2)));
      Number w = clamp(x - Number(k0), 0.0, 1.0);
      vec3 light = mix(slice_a[k0], slice_a[k0 + 1], w);
      vec3 light_mie = vec3(0.0);
      if (order == 2) {
        Number p_sun = mie_phase(u_atmo.mie_g, nu_i);
        light = light * rayleigh_phase(nu_i);
        light_mie = mix(slice_b[k0], slice_b[k0 + 1], w) * p_sun;
        w_s += p_sun * dmu;
      }
      if (ground) {
        vec3 normal = normalize(vec3(0.0, r, 0.0) + omega_i * d_ground);
        light += t_ground * u_atmo.ground_albedo / CV_PI *
                 orders_ground_irradiance(order - 2, clamp(dot(normal, omega_s), -1.0, 1.0));
      }
      Number nu_v = clamp(dot(omega, omega_i), -1.0, 1.0);
      Number p_r = rayleigh_phase(nu_v) * dmu;
      Number p_m = mie_phase(u_atmo.mie_g, nu_v) * dmu;
      j_ra += light * p_r;
      j_rb += light_mie * p_r;
      j_ma += light * p_m;
      j_mb += light_mie * p_m;
      w_r += p_r;
      w_m += p_m;
    }
  }
  // Energy-conserving quadrature: each phase lobe's weights normalised to integrate to one over the
  // grid. The Mie lobes (g = 0.8: most of their weight within 20 degrees) fall between the grid's
  // 11-degree directions, and their sums are off by up to tens of percent from 1 otherwise.
  Number dw = dphi;
  Number n_s = order == 2 && w_s > 0.0 ? 1.0 / (w_s * dw) : 1.0;
  density_r = (j_ra + j_rb * n_s) / max(w_r, 1e-30);
  density_m = (j_ma + j_mb * n_s) / max(w_m, 1e-30);
}

// E_order(mu_s) on the ground: the light of order `order` over the upper hemisphere times cos
// theta, on the ground irradiance LUT's texels and quadrature (compute_irradiance_texel).
vec3 compute_orders_irradiance_texel(int texel, int order) {
  Number mu_s = irradiance_texel_mu_s(texel);
  vec3 s = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), mu_s, 0.0);
  vec3 e = vec3(0.0);
  for (int i = 0; i < CV_IRRADIANCE_BANDS; ++i)
    for (int k = 0; k < CV_IRRADIANCE_SECTORS; ++k) {
      vec3 v = irradiance_direction(i, k);
      e += orders_incident(order, u_atmo.bottom_radius_m, v.y, mu_s, clamp(dot(v, s), -1.0, 1.0)) * v.y;
    }
  return e * irradiance_weight();
}

// L_order at a texel of the orders table: the density (orders parts 3 and 5) integrated along the
// texel's ray, on the per-pixel march's samples (d = d_end x^2).
vec3 compute_orders_multiple_texel(ivec3 texel) {
  Number r = 0.0;
  Number mu = 0.0;
  Number mu_s = 0.0;
  Number nu = 0.0;
  bool hits_ground = false;
  lut4d_texel_geometry(texel, orders_dims(), r, mu, mu_s, nu, hits_ground);
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number d_end = hits_ground ? distance_to_bottom_boundary(r, mu) : distance_to_top_boundary(r, mu);
  vec3 sum = vec3(0.0);
  int n = CV_SKY_SAMPLES;
  for (int i = 0; i < n; ++i) {
    Number x = (Number(i) + 0.5) / Number(n);
    Number d = d_end * x * x;
    Number r_d = clamp(sqrt(d * d + 2.0 * r * mu * d + r * r), bottom, top);
    Number mu_d = clamp((r * mu + d) / r_d, -1.0, 1.0);
    Number mu_s_d = clamp((r * mu_s + d * nu) / r_d, -1.0, 1.0);
    // J = sigma_R(h) A_R + sigma_M(h) A_M: the table holds the A (smooth in altitude), the
    // density profiles are applied here, at the sample's own altitude.
    vec3 j = u_atmo.rayleigh_scattering_per_m * rayleigh_density(r_d - bottom) *
                 orders_lookup(3, r_d, mu_d, mu_s_d, nu, hits_ground) +
             u_atmo.mie_scattering_per_m * mie_density(r_d - bottom) * orders_lookup(5, r_d, mu_d, mu_s_d, nu, hits_ground);
    sum += transmittance_along(r, mu, d, hits_ground) * j * (2.0 * x);
  }
  return sum * (d_end / Number(n));
}

// The 4D LUT's precompute: texel `texel`'s three parts (single Rayleigh, single Mie, orders 2..N),
// the single parts from the per-pixel march's integrals along the whole ray to the boundary the
// texel's half of the mu axis names; the orders from the same march of Psi_ms or, with
// atmosphere.density_orders, read from the orders table's sum.
void compute_scattering_texel(ivec3 texel, OUT(vec3) rayleigh, OUT(vec3) mie, OUT(vec3) multiple) {
  Number r = 0.0;
  Number mu = 0.0;
  Number mu_s = 0.0;
  Number nu = 0.0;
  bool hits_ground = false;
  scattering_texel_geometry(texel, r, mu, mu_s, nu, hits_ground);
  bool density = u_atmo.density_orders > 0.5;
  lut4d_single(r, mu, mu_s, nu, hits_ground, u_atmo.scattering_orders > 1.5 && !density, rayleigh, mie, multiple);
  if (density && u_atmo.scattering_orders > 1.5) multiple = orders_lookup(4, r, mu, mu_s, nu, hits_ground);
}

// The lookup: the three parts at (r, mu, mu_s, nu), linear between the two nearest nu slices.
void scattering_lookup(Number r, Number mu, Number mu_s, Number nu, bool hits_ground, OUT(vec3) rayleigh,
                       OUT(vec3) mie, OUT(vec3) multiple) {
  vec4 uvwz = scattering_uvwz(r, mu, mu_s, nu, hits_ground);
  Number x = uvwz.x * Number(CV_SCATTERING_NU - 1);
  int slice = int(clamp(floor(x), 0.0, Number(CV_SCATTERING_NU - 2)));
  Number w = clamp(x - Number(slice), 0.0, 1.0);
  vec3 uvw = vec3(uvwz.y, uvwz.z, uvwz.w);
  rayleigh = mix(scattering_slice(0, slice, uvw), scattering_slice(0, slice + 1, uvw), w);
  mie = mix(scattering_slice(1, slice, uvw), scattering_slice(1, slice + 1, uvw), w);
  multiple = vec3(0.0);
  if (u_atmo.scattering_orders > 1.5) multiple = mix(scattering_slice(2, slice, uvw), scattering_slice(2, slice + 1, uvw), w);
}

// Where a view ray from altitude `alt` (planet centre straight below, zenith +y) along unit `v`,
// with the sun along unit `s`, starts in the atmosphere: (r, mu, mu_s, nu) there and its distance
// t0 from the camera (0 inside the atmosphere; from space, where the ray enters it). False when
// the ray misses the atmosphere.
bool atmosphere_ray_start(Number alt, vec3 v, vec3 s, OUT(Number) r, OUT(Number) mu, OUT(Number) mu_s,
                          OUT(Number) nu, OUT(Number) t0) {
  Number top = u_atmo.top_radius_m;
  r = u_atmo.bottom_radius_m + clamp(alt, 0.0, 1e9);
  mu = clamp(v.y, -1.0, 1.0);
  mu_s = clamp(s.y, -1.0, 1.0);
  nu = clamp(dot(v, s), -1.0, 1.0);
  t0 = 0.0;
  if (r <= top) return true;
  Number rmu = r * mu;
  Number disc = rmu * rmu - r * r + top * top;
  if (disc < 0.0 || rmu > 0.0) return false;
  t0 = -rmu - sqrt(disc);
  mu = clamp((r * mu + t0) / top, -1.0, 1.0);
  mu_s = clamp((r * mu_s + t0 * nu) / top, -1.0, 1.0);
  r = top;
  return true;
}

// Sunlit ground at the end of a ray that reaches it, (r, mu_s, nu) at the ray's start and d_end
// its length there: albedo / pi * (direct sun + the sky's irradiance), for solar irradiance `solar`.
vec3 atmosphere_ground_radiance(Number r, Number mu_s, Number nu, Number d_end, vec3 solar) {
  Number bottom = u_atmo.bottom_radius_m;
  Number mu_s_g = clamp((r * mu_s + d_end * nu) / bottom, -1.0, 1.0);
  return u_atmo.ground_albedo / CV_PI * solar *
         (transmittance_to_sun(bottom, mu_s_g) * max(mu_s_g, 0.0) + ground_sky_irradiance(mu_s_g));
}

// ------------------------------------------------------------------ the camera's air LUT
// render.air_lut: the sky's integrals seen from one radius r (the camera's) with one sun, as a 3D
// table over the view direction and the distance along the ray, after Hillaire 2020's sky-view
// and aerial-perspective LUTs but in direction space (azimuth from the sun's, elevation), so it
// holds for every camera heading and position at that altitude and changes only with the sun, the
// altitude and the atmosphere. The last distance is the longest ray, so the sky behind everything
// is its last slice. Each texel is the per-pixel march (or the 4D LUT) of its own ray and
// distance, divided by the segment's opacity 1 - T; a lookup is trilinear by hand, like the 4D
// LUT's, never across the horizon, and multiplies by the pixel's own 1 - T (exact, from the
// transmittance LUT). The two parts are before the phase functions (the sun's Mie peak stays exact
// per pixel): single Rayleigh with the orders 2..N divided by the Rayleigh phase at the texel's nu
// (nu changes little between neighbours), and single Mie. Elevation: below and above the horizon
// (cosine air_horizon_mu) each get half the rows, with sqrt spacing from the horizon (Hillaire's),
// texel centres strictly inside their half. Distance: measured from where the ray enters the air.

// The cosine of the horizon's zenith angle from radius r (-1 .. 0; 0 on or below the ground).
Number air_horizon_mu(Number r) {
  Number q = u_atmo.bottom_radius_m / max(r, u_atmo.bottom_radius_m);
  return -atmo_safe_sqrt(1.0 - q * q);
}
// The longest ray through the air from radius r (or from the top, where a ray from higher up
// enters): to the horizon, then on to the top.
Number air_lut_range(Number r) {
  Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
  Number start = min(r, top);
  return atmo_safe_sqrt(start * start - bottom * bottom) + atmo_safe_sqrt(top * top - bottom * bottom);
}
// Distance of depth coordinate w in [0, 1] (slices at w = k / (CV_AIR_DEPTH - 1)), and its inverse.
Number air_lut_distance(Number w, Number range) {
  return range * (exp(CV_AIR_DEPTH_LAMBDA * w) - 1.0) / (exp(CV_AIR_DEPTH_LAMBDA) - 1.0);
}
Number air_lut_depth(Number t, Number range) {
  return log(1.0 + clamp(t / range, 0.0, 1.0) * (exp(CV_AIR_DEPTH_LAMBDA) - 1.0)) / CV_AIR_DEPTH_LAMBDA;
}
// The elevation (radians) of row coordinate a in [0, 1] of one half (0 at the horizon), and back.
Number air_lut_elevation(Number a, bool below, Number horizon) {
  return below ? horizon - a * a * (horizon + 0.5 * CV_PI) : horizon + a * a * (0.5 * CV_PI - horizon);
}
Number air_lut_row(Number elevation, bool below, Number horizon) {
  Number span = below ? horizon + 0.5 * CV_PI : 0.5 * CV_PI - horizon;
  return sqrt(clamp((below ? horizon - elevation : elevation - horizon) / max(span, 1e-9), 0.0, 1.0));
}

// Texel (azimuth, elevation, distance) of the air LUT seen from radius r: the view ray's mu and
// cos(azimuth from the sun's), its length t in the air (from the camera, or from where a ray from
// space enters the air) and which half it is in.
void air_texel_geometry(ivec3 texel, Number r, OUT(Number) mu, OUT(Number) cos_phi, OUT(Number) t, OUT(bool) below) {
  int half_rows = CV_AIR_ELEVATION / 2;
  below = texel.y < half_rows;
  Number a = (Number(below ? half_rows - 1 - texel.y : texel.y - half_rows) + 0.5) / Number(half_rows);
  mu = sin(air_lut_elevation(a, below, asin(air_horizon_mu(r))));
  cos_phi = cos(CV_PI * Number(texel.x) / Number(CV_AIR_AZIMUTH - 1));
  // The first slice a hundredth of the way to the second: the parts' limit at t -> 0 (below).
  t = air_lut_distance(max(Number(texel.z), 0.01) / Number(CV_AIR_DEPTH - 1), air_lut_range(r));
}

// The two parts at (r, mu, mu_s, nu) over the first t metres in the air, whose transmittance
// is `transmittance`, from the LUT: trilinear between the eight nearest texel centres, within the
// half `below` names, times 1 - transmittance (the texels hold the parts divided by it).
void air_lut_parts(Number r, Number mu, Number mu_s, Number nu, Number t, bool below, vec3 transmittance,
                   OUT(vec3) rayleigh, OUT(vec3) mie) {
  int half_rows = CV_AIR_ELEVATION / 2;
  Number horizon = asin(air_horizon_mu(r));
  Number elevation = asin(clamp(mu, -1.0, 1.0));
  Number row = air_lut_row(elevation, below, horizon) * Number(half_rows) - 0.5;
  row = clamp(row, 0.0, Number(half_rows - 1));
  row = below ? Number(half_rows - 1) - row : Number(half_rows) + row;
  // The azimuth from the sun's: cos phi = (nu - mu mu_s) / (sin(view) sin(sun)).
  Number sines = atmo_safe_sqrt(1.0 - mu * mu) * atmo_safe_sqrt(1.0 - mu_s * mu_s);
  Number cos_phi = sines > 1e-6 ? clamp((nu - mu * mu_s) / sines, -1.0, 1.0) : 1.0;
  vec3 p = vec3(acos(cos_phi) / CV_PI * Number(CV_AIR_AZIMUTH - 1), row,
                air_lut_depth(t, air_lut_range(r)) * Number(CV_AIR_DEPTH - 1));
  int lo_row = below ? 0 : half_rows;
  ivec3 i0 = ivec3(clamp(floor(p.x), 0.0, Number(CV_AIR_AZIMUTH - 2)),
                   clamp(floor(p.y), Number(lo_row), Number(lo_row + half_rows - 2)),
                   clamp(floor(p.z), 0.0, Number(CV_AIR_DEPTH - 2)));
  vec3 f = clamp(p - vec3(i0), 0.0, 1.0);
  rayleigh = vec3(0.0);
  mie = vec3(0.0);
  for (int k = 0; k < 8; ++k) {
    ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    Number w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y) * (o.z == 1 ? f.z : 1.0 - f.z);
    rayleigh += w * air_texel(0, i0 + o);
    mie += w * air_texel(1, i0 + o);
  }
  rayleigh *= vec3(1.0) - transmittance;
  mie *= vec3(1.0) - transmittance;
}

// ------------------------------------------------------------------------------ the sky, per ray
// The sky's light along a view ray from altitude `alt` (planet centre straight below, zenith +y)
// along unit `v`, with the sun along unit `s`, for unit solar irradiance at the top of the
// atmosphere, up to the top, the ground or t_max: single Rayleigh and single Mie before their
// phase functions, and the orders 2..N. `transmittance` receives the view ray's transmittance over
// that segment (0 when it ends on the ground), `t_end` its length from the camera (CV_NO_HIT when
// the ray misses the atmosphere) and `ground` the ground's radiance there (albedo / pi * (direct
// sun + the sky's irradiance); 0 when the ray does not end on the ground). Three sources of the
// same integrals (CV_AIR_*):
//  - CV_AIR_MARCH: ray-marched per pixel (scattering_sums: CV_SKY_SAMPLES samples, each reading
//    the transmittance LUT and the multiple-scattering LUT);
//  - CV_AIR_SKY_LUT: read from the 4D scattering LUT. Up to the boundary the ray ends on it is one
//    lookup; a segment that ends sooner, at p (aerial perspective), is Bruneton's
//    S(x) - T(x, p) S(p) (GetSkyRadianceToPoint), with p's lookup in the same half of the mu axis
//    as x's (a ray and its continuation from p reach the same boundary);
//  - CV_AIR_CAMERA_LUT: read from the camera's air LUT (one lookup; only for the `alt` and `s` it
//    was built for), the orders folded into `rayleigh`.
void atmosphere_sky_parts(Number alt, vec3 v, vec3 s, Number t_max, int source, OUT(vec3) rayleigh, OUT(vec3) mie,
                          OUT(vec3) multiple, OUT(vec3) transmittance, OUT(Number) t_end, OUT(vec3) ground) {
  rayleigh = vec3(0.0);
  mie = vec3(0.0);
  multiple = vec3(0.0);
  transmittance = vec3(1.0);
  ground = vec3(0.0);
  t_end = CV_NO_HIT;
  Number r = 0.0;
  Number mu = 0.0;
  Number mu_s = 0.0;
  Number nu = 0.0;
  Number t0 = 0.0;
  if (!atmosphere_ray_start(alt, v, s, r, mu, mu_s, nu, t0)) return;
  bool hits_ground = ray_intersects_ground(r, mu);
  Number d_atmo = hits_ground ? distance_to_bottom_boundary(r, mu) : distance_to_top_boundary(r, mu);
  Number d_end = clamp(t_max - t0, 0.0, d_atmo);
  t_end = t0 + d_end;
  transmittance = transmittance_along(r, mu, d_end, hits_ground);
  if (source == CV_AIR_CAMERA_LUT) {
    Number r_cam = u_atmo.bottom_radius_m + clamp(alt, 0.0, 1e9);
    air_lut_parts(r_cam, clamp(v.y, -1.0, 1.0), clamp(s.y, -1.0, 1.0), nu, d_end, hits_ground, transmittance, rayleigh,
                  mie);
  } else if (source == CV_AIR_SKY_LUT) {
    scattering_lookup(r, mu, mu_s, nu, hits_ground, rayleigh, mie, multiple);
    if (d_end < d_atmo) {
      Number bottom = u_atmo.bottom_radius_m, top = u_atmo.top_radius_m;
      Number r_p = clamp(sqrt(d_end * d_end + 2.0 * r * mu * d_end + r * r), bottom, top);
      Number mu_p = clamp((r * mu + d_end) / r_p, -1.0, 1.0);
      Number mu_s_p = clamp((r * mu_s + d_end * nu) / r_p, -1.0, 1.0);
      vec3 rayleigh_p = vec3(0.0);
      vec3 mie_p = vec3(0.0);
      vec3 multiple_p = vec3(0.0);
      scattering_lookup(r_p, mu_p, mu_s_p, nu, hits_ground, rayleigh_p, mie_p, multiple_p);
      rayleigh = max(rayleigh - transmittance * rayleigh_p, vec3(0.0));
      mie = max(mie - transmittance * mie_p, vec3(0.0));
      multiple = max(multiple - transmittance * multiple_p, vec3(0.0));
    }
  } else {
    scattering_sums(r, mu, mu_s, nu, d_end, hits_ground, u_atmo.scattering_orders > 1.5, rayleigh, mie, multiple);
    Number dx = d_end / Number(CV_SKY_SAMPLES);
    rayleigh *= dx * u_atmo.rayleigh_scattering_per_m;
    mie *= dx * u_atmo.mie_scattering_per_m;
    multiple *= dx;
  }
  if (hits_ground && d_end >= d_atmo) ground = atmosphere_ground_radiance(r, mu_s, nu, d_end, vec3(1.0));
}

// Radiance of the sky along the same ray, for solar irradiance `solar` at the top of the
// atmosphere: atmosphere_sky_parts with the phase functions. `ground` is for `solar` too.
vec3 atmosphere_sky(Number alt, vec3 v, vec3 s, vec3 solar, Number t_max, int source, OUT(vec3) transmittance,
                    OUT(Number) t_end, OUT(vec3) ground) {
  vec3 rayleigh = vec3(0.0);
  vec3 mie = vec3(0.0);
  vec3 multiple = vec3(0.0);
  atmosphere_sky_parts(alt, v, s, t_max, source, rayleigh, mie, multiple, transmittance, t_end, ground);
  ground *= solar;
  Number nu = clamp(dot(v, s), -1.0, 1.0);
  return solar * (rayleigh * rayleigh_phase(nu) + mie * mie_phase(u_atmo.mie_g, nu) + multiple);
}

// A texel of the camera's air LUT for the camera at altitude `alt` and the sun along unit `s`:
// the two parts of its ray over its distance from `source` (CV_AIR_MARCH or CV_AIR_SKY_LUT).
void compute_air_texel(ivec3 texel, Number alt, vec3 s, int source, OUT(vec3) rayleigh, OUT(vec3) mie) {
  Number r = u_atmo.bottom_radius_m + clamp(alt, 0.0, 1e9);
  Number mu = 0.0;
  Number cos_phi = 1.0;
  Number t = 0.0;
  bool below = false;
  air_texel_geometry(texel, r, mu, cos_phi, t, below);
  // The view direction in a frame whose x axis is the sun's azimuth.
  Number mu_s = clamp(s.y, -1.0, 1.0);
  Number sin_v = atmo_safe_sqrt(1.0 - mu * mu);
  vec3 v = vec3(sin_v * cos_phi, mu, sin_v * atmo_safe_sqrt(1.0 - cos_phi * cos_phi));
  vec3 s_frame = vec3(atmo_safe_sqrt(1.0 - mu_s * mu_s), mu_s, 0.0);
  vec3 multiple = vec3(0.0);
  vec3 transmittance = vec3(1.0);
  vec3 ground = vec3(0.0);
  Number t_end = 0.0;
  Number r_in = 0.0, mu_in = 0.0, mu_s_in = 0.0, nu_in = 0.0, t0 = 0.0;  // where the ray enters the air
  if (atmosphere_ray_start(alt, v, s_frame, r_in, mu_in, mu_s_in, nu_in, t0)) t += t0;
  atmosphere_sky_parts(alt, v, s_frame, t, source, rayleigh, mie, multiple, transmittance, t_end, ground);
  rayleigh += multiple / rayleigh_phase(clamp(dot(v, s_frame), -1.0, 1.0));
  // Divided by the segment's opacity: for air of one kind under one light the quotient (the mean
  // source over the extinction) is the same at every distance, so it interpolates far better
  // across slices and rows than the parts, which grow as 1 - T; the lookup's T is exact.
  vec3 opacity = max(vec3(1.0) - transmittance, vec3(1e-7));
  rayleigh /= opacity;
  mie /= opacity;
}

// The sky marched per pixel, and read from the 4D scattering LUT (render.sky_lut).
vec3 atmosphere_scattering(Number alt, vec3 v, vec3 s, vec3 solar, Number t_max, OUT(vec3) transmittance,
                           OUT(Number) t_end, OUT(vec3) ground) {
  return atmosphere_sky(alt, v, s, solar, t_max, CV_AIR_MARCH, transmittance, t_end, ground);
}
vec3 atmosphere_scattering_lut(Number alt, vec3 v, vec3 s, vec3 solar, Number t_max, OUT(vec3) transmittance,
                               OUT(Number) t_end, OUT(vec3) ground) {
  return atmosphere_sky(alt, v, s, solar, t_max, CV_AIR_SKY_LUT, transmittance, t_end, ground);
}

// ------------------------------------------------------------------------------ ground irradiance
// The sky's irradiance on the horizontal ground (Bruneton's indirect irradiance, here of all the
// orders the sky holds) for unit solar irradiance, as a function of the sun's cosine mu_s:
// E(mu_s) = int_hemisphere L_sky(w) cos(theta) dw, from atmosphere_scattering (whose rays from the
// ground upwards never read this LUT). The direct sunlight stays analytic.
vec3 compute_irradiance_texel(int texel) {
  Number mu_s = irradiance_texel_mu_s(texel);
  vec3 s = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), mu_s, 0.0);
  vec3 e = vec3(0.0);
  for (int i = 0; i < CV_IRRADIANCE_BANDS; ++i)
    for (int k = 0; k < CV_IRRADIANCE_SECTORS; ++k) {
      vec3 v = irradiance_direction(i, k);
      vec3 t = vec3(1.0);
      vec3 g = vec3(0.0);
      Number t_end = 0.0;
      e += atmosphere_scattering(0.0, v, s, vec3(1.0), CV_NO_HIT, t, t_end, g) * v.y;
    }
  return e * irradiance_weight();  // d(mu) d(phi), phi over 2 pi
}

// The sun's disc along unit `v` (radiance relative to `disc_radiance`): limb darkening
// 1 - 0.6 (1 - cos theta) across the disc (theta: the angle at the sun's surface), an anti-aliased
// rim, and the transmittance to the top (0 where the line of sight hits the ground: a partial set).
vec3 atmosphere_sun_disc(Number alt, vec3 v, vec3 s, vec3 disc_radiance) {
  Number r = u_atmo.bottom_radius_m + clamp(alt, 0.0, 1e9);
  Number alpha = u_atmo.sun_angular_radius;
  Number c = clamp(dot(v, s), -1.0, 1.0);
  // Away from the disc without the acos (most of the sky): 1 - cos(angle) <= angle^2 / 2, so
  // 1 - c above (1.2 alpha)^2 / 2 (with 10 % to spare for rounding) means angle > 1.2 alpha, where
  // the test below returns 0 as well.
  if (1.0 - c > 0.55 * (1.2 * alpha) * (1.2 * alpha)) return vec3(0.0);
  Number angle = acos(c);
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
