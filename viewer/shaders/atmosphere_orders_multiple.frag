#version 450 core
// Precompute pass (atmosphere.density_orders): the light of one order, the density integrated along
// each texel's ray (compute_orders_multiple_texel), written as the last order (attachment 0) and
// added to the sum (attachment 1, additive blending), one layer per draw.
#define CV_ATMOSPHERE_ORDERS 1
#include "atmosphere_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out vec4 o_delta;
layout(location = 1) out vec4 o_sum;
void main() {
  vec3 delta = compute_orders_multiple_texel(ivec3(ivec2(gl_FragCoord.xy), u_layer));
  o_delta = vec4(delta, 1.0);
  o_sum = vec4(delta, 0.0);
}
