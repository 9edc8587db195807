// The precomputed atmosphere (atmosphere.glsl) as the cloud passes use it with render.sky=precomputed:
// the sky behind everything, the sun's colour at a cloud or ground point, and the ambient sky
// light. The camera sits at altitude u_cloud.sky_altitude_m with the planet's centre straight below
// (world +y is the local zenith). Needs atmosphere.glsl and `u_cloud`.

bool sky_precomputed() { return int(CV_MODE_SKY) == CV_SKY_PRECOMPUTED; }

// Sun colour reaching camera-relative point p (top-of-atmosphere colour u_cloud.sun_color times
// the transmittance from p to the sun; 0 in the Earth's shadow). The analytic sky: the constant.
// Every cloud sample that is lit asks for it, so the GPU reads the transmittance LUT through its
// texture unit (one filtered fetch; render.exact_filter and the CPU reference: the same bilinear
// by hand from four texels, atmosphere.glsl transmittance_bilinear).
vec3 sun_color_at(vec3 p) {
  if (!sky_precomputed()) return u_cloud.sun_color;
  vec3 c = p + vec3(0.0, u_atmo.bottom_radius_m + u_cloud.sky_altitude_m, 0.0);  // from the planet's centre
  Number len = length(c);
  Number r = clamp(len, u_atmo.bottom_radius_m, u_atmo.top_radius_m);
  Number mu_s = clamp(dot(c, u_cloud.sun_dir) / max(len, 1.0), -1.0, 1.0);
  vec2 uv = transmittance_uv(r, mu_s);
  vec3 top = CV_MODE_EXACT_FILTER > 0.5 ? transmittance_bilinear(uv) : transmittance_filtered(uv);
  return u_cloud.sun_color * top * sun_disc_visible(r, mu_s);
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

// Aerial perspective: the light the air scatters towards the camera over the first t metres of
// camera ray rd (`inscattered`) and the air's transmittance over them (RGB: `transmittance`).
void air_segment(vec3 rd, Number t, OUT(vec3) inscattered, OUT(vec3) transmittance) {
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  vec3 ground = vec3(0.0);
  Number t_end = 0.0;
  inscattered = sky_scattering(rd, solar, t, transmittance, t_end, ground);
}

// The air in front of the background along rd (temporal upsampling samples it at 1/16 of the
// pixels): `inscattered` is the sky without the sun's disc for a ray that sees no ground
// (t_scene >= CV_NO_HIT_TEST, `transmittance` 0; the far ground beyond the ground pass's mesh,
// sunlit with albedo atmosphere.ground_albedo, seen through the air, included), else the light the
// air scatters over the t_scene metres to the ground and their transmittance. One integral serves
// both kinds of pixel, up to the end of the ray or to t_scene: llvmpipe would evaluate both of two
// per-pixel alternatives.
void background_air(vec3 rd, Number t_scene, OUT(vec3) inscattered, OUT(vec3) transmittance) {
  bool sky = t_scene >= CV_NO_HIT_TEST;
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  vec3 ground = vec3(0.0);
  vec3 t_air = vec3(1.0);
  Number t_end = 0.0;
  inscattered = sky_scattering(rd, solar, sky ? CV_NO_HIT : t_scene, t_air, t_end, ground);
  if (sky) inscattered += t_air * ground;
  transmittance = sky ? vec3(0.0) : t_air;
}

// The sun's disc along rd (the sharp part of the sky, always per pixel).
vec3 precomputed_sun_disc(vec3 rd) {
  vec3 solar = u_cloud.sun_color * u_cloud.sun_radiance;
  return atmosphere_sun_disc(u_cloud.sky_altitude_m, rd, u_cloud.sun_dir, solar * u_cloud.sun_disc_scale);
}

// The background from its air (background_air's outputs): the sky with the sun's disc, or the
// ground's radiance `scene_color` seen through the air.
vec3 background_through_air(vec3 rd, bool sky, vec3 scene_color, vec3 inscattered, vec3 transmittance) {
  return sky ? inscattered + precomputed_sun_disc(rd) : scene_color * transmittance + inscattered;
}

// The sky behind everything along rd.
vec3 precomputed_sky_radiance(vec3 rd) {
  vec3 inscattered = vec3(0.0);
  vec3 transmittance = vec3(1.0);
  background_air(rd, CV_NO_HIT, inscattered, transmittance);
  return background_through_air(rd, true, vec3(0.0), inscattered, transmittance);
}
