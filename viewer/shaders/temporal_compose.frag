#version 450 core
// Temporal upsampling, step 3: the resolved cloud layer over the full-resolution background (sky,
// or the ground through the air), the same compose_over as the full-resolution cloud pass.
#include "cloud_headers.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_cloud;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_scene_distance;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 rd = pixel_ray(u_inv_view_proj, gl_FragCoord.xy, u_viewport.xy);
  vec4 m = texelFetch(s_cloud, px, 0);
  o_color = vec4(compose_over(m, rd, texelFetch(s_scene_distance, px, 0).r, texelFetch(s_scene_color, px, 0).rgb), 1.0);
}
