// One pixel of the cloud pass (Olajos 2016, thesis 2.4: deferred shading and ray casting): march the
// camera ray up to the scene distance, fade with aerial perspective, composite over the background
// (L_cloud + T * L_scene), or write a debug output. cloud.frag calls it with the ground pass's
// outputs, the CPU reference with its own ground intersection: one compose for both.
// Needs every header up to sky.glsl.

// The cloud layer seen along `rd` (camera-relative, unit) up to the scene distance `t_scene`:
// (in-scattered radiance after aerial perspective, transmittance). `pixel` picks the jitter;
// `t_mean` is the cloud's opacity-weighted distance (0: no cloud), `iterations` the loop trips.
vec4 cloud_layer(vec3 rd, ivec2 pixel, Number t_scene, OUT(Number) t_mean, OUT(int) iterations) {
  Number jitter = u_cloud.jitter > 0.5 ? jitter_offset(pixel, int(u_cloud.frame_index)) : 0.5;
  iterations = 0;
  t_mean = 0.0;
  vec4 m = march_clouds(rd, t_scene, jitter, iterations, t_mean);
  return aerial_perspective(m, t_mean, rd);
}

// The cloud layer `m` composited over what lies behind it: the sky, or the ground at `t_scene`
// (>= CV_NO_HIT_TEST: none) with radiance `scene_color` seen through the air. Linear HDR; the
// transmittance output writes T instead.
vec3 compose_over(vec4 m, vec3 rd, Number t_scene, vec3 scene_color) {
  if (int(CV_MODE_OUTPUT) == CV_OUTPUT_TRANSMITTANCE) return vec3(m.w, m.w, m.w);
  vec3 background = vec3(0.0);
  if (sky_precomputed()) {
    vec3 inscattered = vec3(0.0);
    vec3 transmittance = vec3(1.0);
    background_air(rd, t_scene, inscattered, transmittance);
    background = background_through_air(rd, t_scene >= CV_NO_HIT_TEST, scene_color, inscattered, transmittance);
  } else {
    background = t_scene >= CV_NO_HIT_TEST ? sky_radiance(rd) : scene_color;
  }
  return vec3(m) + m.w * background;
}

// `rd`: unit camera-relative ray; `pixel`: window pixel (jitter pattern); `t_scene`: distance to the
// ground (>= CV_NO_HIT_TEST: none); `scene_color`: ground radiance there. Returns linear HDR.
vec3 compose_pixel(vec3 rd, ivec2 pixel, Number t_scene, vec3 scene_color) {
  int iterations = 0;
  Number t_mean = 0.0;
  vec4 m = cloud_layer(rd, pixel, t_scene, t_mean, iterations);
  if (int(CV_MODE_OUTPUT) == CV_OUTPUT_ITERATIONS) return vec3(Number(iterations), m.w, 0.0);
  return compose_over(m, rd, t_scene, scene_color);
}
