#version 450 core
// HDR resolve (thesis 2.7): add the blurred bloom before tone mapping, expose, tone map
// (Reinhard L/(1+L) or ACES filmic), encode sRGB. Writes the display image and the linear HDR frame.
#include "prelude_glsl.glsl"
#include "cloud_params.glsl"
#include "bindings.glsl"
#include "cloud_functions.glsl"
#include "post_common.glsl"
layout(binding = 3) uniform sampler2D s_hdr;
layout(binding = 4) uniform sampler2D s_bloom;
layout(location = 0) out vec4 o_display;
layout(location = 1) out vec4 o_linear;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 hdr = texelFetch(s_hdr, px, 0).rgb;
  if (u_post.z > 0.0) hdr += u_post.z * bilinear_fetch(s_bloom, gl_FragCoord.xy / u_viewport.xy);
  o_display = vec4(srgb_encode(tone_map(hdr, u_post.x, int(u_post.y))), 1.0);
  o_linear = vec4(hdr, 1.0);
}
