// Temporal upsampling, step 3: the resolved cloud layer over the full-resolution background. With
// the precomputed sky the air in front of the background (smooth over the image) comes from the
// sparse pixels: a bilinear filter over the four blocks around this pixel, normalised by the
// filtered weight so that only the blocks that hold this pixel's kind of background (sky, or
// ground) count (cloud_sparse.frag stores both kinds where a block holds both, so this pixel's
// own block, whose bilinear weight is at least 1/16, always has it). Toward the ground the
// filtered quantities are the air's extinction and in-scattering per metre (temporal.glsl), so
// the air is evaluated once, at this pixel's own distance: the far ground near the horizon,
// whose distance changes fast from row to row, can use its neighbours. The ground's own
// radiance, its shadows and the sun's disc stay per pixel. The analytic sky is cheap:
// compose_over as the full cloud pass does. A held frame (nothing moved) does not run this pass:
// cloud_sparse_held.frag composes the pixels it marched over last frame's image.
// Both stages run it: temporal_compose.frag, and temporal_compose.comp with render.compute.
// compose_main() writes the outputs at the pixel centre g_frag (gl_FragCoord.xy, or the compute
// invocation's + 0.5).
vec2 g_frag;
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_cloud;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_scene_distance;
layout(binding = CV_UNIT_PASS_INPUT3) uniform sampler2D s_air;      // quarter, ground: extinction, weight
layout(binding = CV_UNIT_PASS_INPUT4) uniform sampler2D s_air_e;    // quarter, ground: in-scattering, weight
layout(binding = CV_UNIT_PASS_INPUT5) uniform sampler2D s_air_sky;  // quarter, sky: inscattered, weight

vec3 background(ivec2 px, vec3 rd, float t, vec3 scene_color) {
  bool sky = t >= CV_NO_HIT_TEST;
  // Fresh texel (i, j) sits at full-resolution pixel 4 (i, j) + u_temporal.zw (linear filtering,
  // clamped to the edge, as the resolve's bilinear upsample).
  vec2 uv = ((vec2(px) - u_temporal.zw) * 0.25 + 0.5) / vec2(textureSize(s_air, 0));
  vec3 inscattered = vec3(0.0), transmittance = vec3(0.0);
  if (sky) {
    vec4 a = texture(s_air_sky, uv);
    inscattered = a.rgb / max(a.w, 1e-6);
  } else {
    vec4 a = texture(s_air, uv);
    vec3 e = texture(s_air_e, uv).rgb;
    float w = max(a.w, 1e-6);
    air_over_distance(a.rgb / w, e / w, t, inscattered, transmittance);
  }
  return background_through_air(rd, sky, scene_color, inscattered, transmittance);
}

void compose_main() {
  ivec2 px = ivec2(g_frag);
  vec3 rd = pixel_ray(u_inv_view_proj, g_frag, u_viewport.xy);
  vec4 m = texelFetch(s_cloud, px, 0);
  float t = texelFetch(s_scene_distance, px, 0).r;
  vec3 scene_color = texelFetch(s_scene_color, px, 0).rgb;
  if (!sky_precomputed() || int(CV_MODE_OUTPUT) == CV_OUTPUT_TRANSMITTANCE) {
    o_color = vec4(compose_over(m, rd, t, scene_color), 1.0);
    return;
  }
  o_color = vec4(vec3(m) + m.w * background(px, rd, t, scene_color), 1.0);
}
