#version 450 core
// Bloom step 2: one direction of the separable Gaussian blur at reduced resolution.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "post.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_source;
layout(location = 0) uniform ivec2 u_direction;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  ivec2 n = textureSize(s_source, 0);
  vec3 acc = vec3(0.0);
  for (int i = -CV_BLOOM_RADIUS; i <= CV_BLOOM_RADIUS; ++i) {
    ivec2 q;
    Number w = bloom_tap(px, u_direction, i, n, q);
    acc += w * texelFetch(s_source, q, 0).rgb;
  }
  o_color = vec4(acc, 1.0);
}
