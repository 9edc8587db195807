// Temporal upsampling, step 1 (seed 003): the cloud layer of one pixel per 4x4 block, the one the
// cross matrix picks for this frame (u_temporal.zw), into a quarter-by-quarter target: (radiance,
// transmittance) after aerial perspective, and the cloud's opacity-weighted distance (0: none)
// that the resolve reprojects with. With the precomputed sky also the air in front of the
// background at the same pixel (background_air; smooth, so temporal_compose upsamples it), for
// each kind of background the block holds: the sky (inscattered light to the top of the air) and
// the ground (the air's extinction and in-scattering per metre up to the ground, temporal.glsl's
// air_coefficients), each with a weight of 1 where the block has it and all 0 where it has not, so
// that a bilinear filter over them and a division by the filtered weight averages only the blocks
// that hold the kind (a normalised convolution). The kind this pixel
// does not see is taken at the block's nearest pixel that sees it, when there is one, so every
// full-resolution pixel finds its own kind in its own block and temporal_compose never marches
// the air itself (a per-pixel fallback cost every pixel its time on llvmpipe, which runs both
// sides of a branch).
// Both stages run it: cloud_sparse.frag, and cloud_sparse.comp with render.compute.
// sparse_main() writes the outputs at the pixel centre g_frag (gl_FragCoord.xy, or the compute
// invocation's + 0.5).
vec2 g_frag;
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_scene_distance;
// Writes the air in front of the background at distance t along `ray` into the outputs of its
// kind (the sky when t >= CV_NO_HIT_TEST, else the ground).
void store_background_air(vec3 ray, float t) {
  vec3 inscattered = vec3(0.0), transmittance = vec3(1.0);
  background_air(ray, t, inscattered, transmittance);
  if (t >= CV_NO_HIT_TEST) {
    o_air_sky = vec4(inscattered, 1.0);
  } else {
    vec3 s = vec3(0.0), e = vec3(0.0);
    air_coefficients(inscattered, transmittance, t, s, e);
    o_air = vec4(s, 1.0);
    o_air_e = vec4(e, 1.0);
  }
}
void sparse_main() {
  ivec2 full = ivec2(g_frag) * 4 + ivec2(u_temporal.zw);
  full = min(full, ivec2(u_viewport.xy) - 1);  // a partial block at the right or top edge
  vec3 rd = pixel_ray(u_inv_view_proj, vec2(full) + 0.5, u_viewport.xy);
  float t_scene = texelFetch(s_scene_distance, full, 0).r;
  float t_mean = 0.0;
  int iterations = 0;
  o_cloud = cloud_layer(rd, full, t_scene, t_mean, iterations);
  o_depth = vec4(t_mean, 0.0, 0.0, 0.0);
  o_air = vec4(0.0);
  o_air_e = vec4(0.0);
  o_air_sky = vec4(0.0);
  if (!sky_precomputed()) return;
  store_background_air(rd, t_scene);
  // The block's nearest pixel that sees the other kind, when there is one.
  bool sky = t_scene >= CV_NO_HIT_TEST;
  ivec2 base = ivec2(g_frag) * 4;
  bool found = false;
  int best = 0;
  ivec2 other = full;
  float t_other = 0.0;
  for (int i = 0; i < 16; ++i) {
    ivec2 q = min(base + ivec2(i & 3, i >> 2), ivec2(u_viewport.xy) - 1);
    float tq = texelFetch(s_scene_distance, q, 0).r;
    ivec2 d = q - full;
    int d2 = d.x * d.x + d.y * d.y;
    if ((tq >= CV_NO_HIT_TEST) != sky && (!found || d2 < best)) {
      found = true;
      best = d2;
      other = q;
      t_other = tq;
    }
  }
  if (found) store_background_air(pixel_ray(u_inv_view_proj, vec2(other) + 0.5, u_viewport.xy), t_other);
}
