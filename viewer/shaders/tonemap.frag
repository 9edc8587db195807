#version 450 core
// HDR resolve (thesis 2.7): add the blurred bloom before tone mapping, expose, tone map
// (Reinhard L/(1+L) or ACES filmic), encode sRGB. Writes the display image and the linear HDR frame.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_hdr;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_bloom;
layout(location = 0) out vec4 o_display;
layout(location = 1) out vec4 o_linear;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 hdr = texelFetch(s_hdr, px, 0).rgb;
  if (u_post.z > 0.0) hdr += u_post.z * bilinear_fetch(s_bloom, gl_FragCoord.xy / u_viewport.xy);
  o_display = vec4(display_encode(hdr, u_post.x, int(u_post.y)), 1.0);
  o_linear = vec4(hdr, 1.0);
}
