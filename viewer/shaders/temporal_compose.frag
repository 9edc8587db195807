#version 450 core
// Temporal upsampling, step 3: the resolved cloud layer over the full-resolution background. With
// the precomputed sky the air in front of the background (smooth over the image) comes from the
// sparse pixels: bilinear over the four blocks around this pixel that hold its kind of background
// (sky, or ground; cloud_sparse.frag stores both kinds where a block holds both, so this pixel's
// own block, whose bilinear weight is at least 1/16, always has it). A ground neighbour's air is
// carried to this pixel's distance t as if the air along the ray were uniform (transmittance
// T^(t / t_k), inscattered light in proportion to 1 - T): exact for a uniform medium, and nearly
// so between rays 4 pixels apart, which is what lets the far ground near the horizon, whose
// distance changes fast from row to row, use its neighbours. The ground's own radiance, its
// shadows and the sun's disc stay per pixel. The analytic sky is cheap: compose_over as the full
// cloud pass does.
#include "cloud_headers.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_cloud;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_scene_distance;
layout(binding = CV_UNIT_PASS_INPUT3) uniform sampler2D s_air;      // quarter, ground: inscattered, distance (0: none)
layout(binding = CV_UNIT_PASS_INPUT4) uniform sampler2D s_air_t;    // quarter, ground: transmittance
layout(binding = CV_UNIT_PASS_INPUT5) uniform sampler2D s_air_sky;  // quarter, sky: inscattered, 1 (0: none)
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
    float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    if (sky) {
      vec4 a = texelFetch(s_air_sky, q, 0);
      if (a.w < 0.5) continue;
      inscattered += w * a.rgb;
    } else {
      vec4 a = texelFetch(s_air, q, 0);
      if (!(a.w > 0.0)) continue;
      vec3 tk = texelFetch(s_air_t, q, 0).rgb;
      float r = t / a.w;
      vec3 tt = pow(max(tk, vec3(1e-6)), vec3(r));
      vec3 lost = vec3(1.0) - tk;
      // I(t) = I_k (1 - T(t)) / (1 - T_k); for nearly clear air (1 - T_k -> 0) the limit I_k t / t_k.
      vec3 scale = mix(vec3(r), (vec3(1.0) - tt) / max(lost, vec3(1e-6)), step(vec3(1e-4), lost));
      inscattered += w * a.rgb * scale;
      transmittance += w * tt;
    }
    wsum += w;
  }
  inscattered /= max(wsum, 1e-6);
  transmittance /= max(wsum, 1e-6);
  return background_through_air(rd, sky, scene_color, inscattered, transmittance);
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 rd = pixel_ray(u_inv_view_proj, gl_FragCoord.xy, u_viewport.xy);
  vec4 m = texelFetch(s_cloud, px, 0);
  float t = texelFetch(s_scene_distance, px, 0).r;
  vec3 scene_color = texelFetch(s_scene_color, px, 0).rgb;
  if (!sky_precomputed() || int(CV_MODE_OUTPUT) == CV_OUTPUT_TRANSMITTANCE) {
    o_color = vec4(compose_over(m, rd, t, scene_color), 1.0);
    return;
  }
  o_color = vec4(vec3(m) + m.w * background(px, rd, t, scene_color), 1.0);
}
