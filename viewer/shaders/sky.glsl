// Background sky and aerial perspective: the analytic model (render.sky=analytic, CV_SKY_ANALYTIC)
// or the precomputed atmosphere (sky_atmosphere.glsl, CV_SKY_PRECOMPUTED), chosen by CV_MODE_SKY.
// Needs constants.glsl, medium.glsl (layer_mode), sky_atmosphere.glsl and `u_cloud`.

// Horizon-to-zenith gradient and a soft sun disc.
vec3 sky_radiance(vec3 rd) {
  if (sky_precomputed()) return precomputed_sky_radiance(rd);
  vec3 sun = u_cloud.sun_dir;
  vec3 zenith = u_cloud.sky_zenith;
  vec3 horizon = mix(zenith, vec3(1.0), 0.55);
  Number up = clamp(rd.y, 0.0, 1.0);
  vec3 sky = mix(horizon, zenith, sqrt(up));
  if (rd.y < 0.0) sky = horizon * 0.6;
  Number cos_sun = dot(rd, sun);
  Number disc = smoothstep(0.99994, 0.99998, cos_sun);
  return sky + u_cloud.sun_color * (u_cloud.sun_disc_scale * disc);
}

// Aerial perspective for layer mode: distant clouds fade into the horizon sky with a 30 km scale
// (Beer-Lambert of a clear atmosphere's haze), which also hides their sampling noise at the horizon.
// `cloud` is (radiance, transmittance) from march_clouds; returns the faded pair.
vec4 aerial_perspective(vec4 cloud, Number t_mean, vec3 rd) {
  if (sky_precomputed()) {  // both modes: the atmosphere between the camera and the clouds' mean depth
    if (cloud.w >= 1.0) return cloud;
    vec3 inscattered = vec3(0.0);
    vec3 transmittance = vec3(1.0);
    air_segment(rd, t_mean, inscattered, transmittance);
    return vec4(vec3(cloud) * transmittance + inscattered * (1.0 - cloud.w), cloud.w);
  }
  if (!layer_mode() || cloud.w >= 1.0) return cloud;
  Number haze = 1.0 - exp(-t_mean / 30000.0);
  vec3 sky = sky_radiance(vec3(rd.x, max(rd.y, 0.0), rd.z));
  vec3 faded = mix(vec3(cloud), sky * (1.0 - cloud.w), haze);
  return vec4(faded, cloud.w);
}
