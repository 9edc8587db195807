#version 450 core
// Temporal upsampling, step 3: the resolved cloud layer over the full-resolution background. With
// the precomputed sky the air in front of the background (smooth over the image) comes from the
// sparse pixels: bilinear over the four around this pixel that see the same kind of background
// (sky, or ground within 5% of this pixel's distance); where none does (edges of the ground, the
// horizon) it is evaluated here. The ground's own radiance, its shadows and the sun's disc stay
// per pixel. The analytic sky is cheap: compose_over as the full cloud pass does.
#include "cloud_headers.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_cloud;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_scene_distance;
layout(binding = CV_UNIT_PASS_INPUT3) uniform sampler2D s_air;    // quarter: inscattered, scene distance
layout(binding = CV_UNIT_PASS_INPUT4) uniform sampler2D s_air_t;  // quarter: transmittance
layout(location = 0) out vec4 o_color;

vec3 background(ivec2 px, vec3 rd, float t, vec3 scene_color) {
  bool sky = t >= CV_NO_HIT_TEST;
  ivec2 off = ivec2(u_temporal.zw);
  ivec2 qn = textureSize(s_air, 0);
  vec2 g = (vec2(px) - vec2(off)) / 4.0;
  ivec2 g0 = ivec2(floor(g));
  vec2 f = g - vec2(g0);
  vec3 inscattered = vec3(0.0), transmittance = vec3(0.0);
  float wsum = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 q = clamp(g0 + o, ivec2(0), qn - 1);
    vec4 a = texelFetch(s_air, q, 0);
    bool q_sky = a.w >= CV_NO_HIT_TEST;
    bool same = sky ? q_sky : (!q_sky && abs(a.w - t) <= 0.05 * t);
    float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    if (same) {
      inscattered += w * a.rgb;
      transmittance += w * texelFetch(s_air_t, q, 0).rgb;
      wsum += w;
    }
  }
  if (wsum >= 0.2) {
    inscattered /= wsum;
    transmittance /= wsum;
  } else {
    background_air(rd, t, inscattered, transmittance);
  }
  return sky ? inscattered + precomputed_sun_disc(rd) : scene_color * transmittance + inscattered;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 rd = pixel_ray(u_inv_view_proj, gl_FragCoord.xy, u_viewport.xy);
  vec4 m = texelFetch(s_cloud, px, 0);
  float t = texelFetch(s_scene_distance, px, 0).r;
  vec3 scene_color = texelFetch(s_scene_color, px, 0).rgb;
  if (!sky_precomputed() || int(u_cloud.output_mode) == CV_OUTPUT_TRANSMITTANCE) {
    o_color = vec4(compose_over(m, rd, t, scene_color), 1.0);
    return;
  }
  o_color = vec4(vec3(m) + m.w * background(px, rd, t, scene_color), 1.0);
}
