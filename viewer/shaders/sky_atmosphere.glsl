// The precomputed atmosphere (atmosphere.glsl) as the cloud passes use it with render.sky=precomputed:
// the sky behind everything, the sun's colour at a cloud or ground point, and the ambient sky
// light. The camera sits at altitude u_cloud.sky_altitude_m with the planet's centre straight below
// (world +y is the local zenith). Needs atmosphere.glsl and `u_cloud`.

bool sky_precomputed() { return int(CV_MODE_SKY) == CV_SKY_PRECOMPUTED; }

// Sun colour reaching camera-relative point p (top-of-atmosphere colour u_cloud.sun_color times
// the transmittance from p to the sun; 0 in the Earth's shadow). The analytic sky: the constant.
vec3 sun_color_at(vec3 p) {
  if (!sky_precomputed()) return u_cloud.sun_color;
  vec3 c = p + vec3(0.0, u_atmo.bottom_radius_m + u_cloud.sky_altitude_m, 0.0);  // from the planet's centre
  Number r = clamp(length(c), u_atmo.bottom_radius_m, u_atmo.top_radius_m);
  Number mu_s = clamp(dot(c, u_cloud.sun_dir) / max(length(c), 1.0), -1.0, 1.0);
  return u_cloud.sun_color * transmittance_to_sun(r, mu_s);
}

// Where the frame's sky comes from (CV_AIR_*): the camera's air LUT (render.air_lut), the 4D
// scattering LUT (render.sky_lut) or the per-pixel march; the air LUT's own texels from the other two.
int sky_source() {
  return CV_MODE_AIR_LUT > 0.5 ? CV_AIR_CAMERA_LUT : CV_MODE_SKY_LUT > 0.5 ? CV_AIR_SKY_LUT : CV_AIR_MARCH;
}
int air_lut_source() { return CV_MODE_SKY_LUT > 0.5 ? CV_AIR_SKY_LUT : CV_AIR_MARCH; }

// The air's light along camera ray rd up to t_max (atmosphere_scattering's arguments and outputs).
vec3 sky_scattering(vec3 rd, vec3 solar, Number t_max, OUT(vec3) transmittance, OUT(Number) t_end, OUT(vec3) ground) {
  return atmosphere_sky(u_cloud.sky_altitude_m, rd, u_cloud.sun_dir, solar, t_max, sky_source(), transmittance, t_end,
                        ground);
}

// A texel of the camera's air LUT for this frame's camera altitude and sun (air_lut.frag).
void frame_air_texel(ivec3 texel, OUT(vec3) rayleigh, OUT(vec3) mie) {
  compute_air_texel(texel, u_cloud.sky_altitude_m, u_cloud.sun_dir, air_lut_source(), rayleigh, mie);
}

// Background radiance along camera ray rd: single scattering, the ground beyond the ground pass's
// mesh (sunlit, albedo atmosphere.ground_albedo) seen through the air, and the sun's disc.
// precomputed_sky_air is the smooth part (scattering and the far ground), precomputed_sun_disc the
// sharp one: temporal upsampling evaluates the first at 1/16 of the pixels.
vec3 precomputed_sky_air(vec3 rd) {
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  vec3 transmittance = vec3(1.0);
  vec3 ground = vec3(0.0);
  Number t_end = 0.0;
  vec3 sky = sky_scattering(rd, solar, CV_NO_HIT, transmittance, t_end, ground);
  return sky + transmittance * ground;
}
vec3 precomputed_sun_disc(vec3 rd) {
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  return atmosphere_sun_disc(u_cloud.sky_altitude_m, rd, u_cloud.sun_dir, solar * u_cloud.sun_disc_scale);
}
vec3 precomputed_sky_radiance(vec3 rd) { return precomputed_sky_air(rd) + precomputed_sun_disc(rd); }

// Aerial perspective: the light the air scatters towards the camera over the first t metres of
// camera ray rd (`inscattered`) and the air's transmittance over them (RGB: `transmittance`).
void air_segment(vec3 rd, Number t, OUT(vec3) inscattered, OUT(vec3) transmittance) {
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  vec3 ground = vec3(0.0);
  Number t_end = 0.0;
  inscattered = sky_scattering(rd, solar, t, transmittance, t_end, ground);
}
