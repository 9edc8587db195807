#version 450 core
// Full-screen cloud pass (Olajos 2016, thesis 2.4: deferred shading and ray casting). Each pixel's
// world ray comes from the inverse view-projection; compose_pixel (compose.glsl, shared with the
// CPU reference) marches up to the scene distance written by the ground pass and composites over it.
#include "cloud_headers.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_distance;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 rd = pixel_ray(u_inv_view_proj, gl_FragCoord.xy, u_viewport.xy);
  float t_scene = texelFetch(s_scene_distance, px, 0).r;
  o_color = vec4(compose_pixel(rd, px, t_scene, texelFetch(s_scene_color, px, 0).rgb), 1.0);
}
