#version 450 core
// Bloom step 2: one direction of the separable Gaussian blur at reduced resolution.
#include "prelude_glsl.glsl"
#include "cloud_params.glsl"
#include "bindings.glsl"
#include "cloud_functions.glsl"
#define BLOOM_RADIUS 6
#define BLOOM_SIGMA 3.0
layout(binding = 3) uniform sampler2D s_source;
layout(location = 0) uniform ivec2 u_direction;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  ivec2 n = textureSize(s_source, 0);
  vec3 acc = vec3(0.0);
  for (int i = -BLOOM_RADIUS; i <= BLOOM_RADIUS; ++i) {
    ivec2 q = clamp(px + u_direction * i, ivec2(0), n - 1);
    acc += gaussian_weight(i, BLOOM_RADIUS, BLOOM_SIGMA) * texelFetch(s_source, q, 0).rgb;
  }
  o_color = vec4(acc, 1.0);
}
