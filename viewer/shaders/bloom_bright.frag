#version 450 core
// Bloom step 1 (thesis 2.7): downsample the HDR frame to half resolution and keep what is brighter
// than the threshold.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_hdr;
layout(location = 0) out vec4 o_color;
void main() {
  vec3 c = bilinear_fetch(s_hdr, gl_FragCoord.xy / u_viewport.zw);
  o_color = vec4(bloom_bright(c, u_post.w), 1.0);
}
