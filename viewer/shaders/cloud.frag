#version 450 core
// Full-screen cloud pass (Olajos 2016, thesis 2.4: deferred shading and ray casting). Each pixel's
// world ray comes from the inverse view-projection; the march stops at the scene distance written
// by the ground pass and composites over it: L_cloud + T * L_scene.
#include "prelude_glsl.glsl"
#include "cloud_params.glsl"
#include "bindings.glsl"
#include "cloud_functions.glsl"
layout(binding = 3) uniform sampler2D s_scene_color;
layout(binding = 4) uniform sampler2D s_scene_distance;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec2 ndc = gl_FragCoord.xy / u_viewport.xy * 2.0 - 1.0;
  vec4 near_point = u_inv_view_proj * vec4(ndc, -1.0, 1.0);
  vec3 rd = normalize(near_point.xyz / near_point.w);
  float t_scene = texelFetch(s_scene_distance, px, 0).r;
  float jitter = u_cloud.control.x > 0.5 ? jitter_offset(px, int(u_cloud.control.y)) : 0.5;
  int iterations;
  float t_mean;
  vec4 m = march_clouds(rd, t_scene, jitter, iterations, t_mean);
  m = aerial_perspective(m, t_mean, rd);
  int mode = int(u_cloud.control.w);
  if (mode == 1) { o_color = vec4(m.w, m.w, m.w, 1.0); return; }
  if (mode == 2) { o_color = vec4(float(iterations), m.w, 0.0, 1.0); return; }
  vec3 background = t_scene >= 1e29 ? sky_radiance(rd) : texelFetch(s_scene_color, px, 0).rgb;
  o_color = vec4(m.xyz + m.w * background, 1.0);
}
