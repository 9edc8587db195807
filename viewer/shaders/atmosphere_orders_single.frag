#version 450 core
// Precompute pass (atmosphere.density_orders): the orders table's single Rayleigh and single Mie
// parts (atmosphere.glsl, compute_orders_single_texel), one layer (an r texel) per draw.
#define CV_ATMOSPHERE_ORDERS 1
#include "atmosphere_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out vec4 o_rayleigh;
layout(location = 1) out vec4 o_mie;
void main() {
  vec3 rayleigh, mie;
  compute_orders_single_texel(ivec3(ivec2(gl_FragCoord.xy), u_layer), rayleigh, mie);
  o_rayleigh = vec4(rayleigh, 1.0);
  o_mie = vec4(mie, 1.0);
}
