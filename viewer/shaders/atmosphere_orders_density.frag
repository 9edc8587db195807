#version 450 core
// Precompute pass (atmosphere.density_orders): the scattering density J of order u_order from the
// light of the order before and the ground's irradiance of the one before that
// (compute_density_texel), one layer per draw.
#define CV_ATMOSPHERE_ORDERS 1
#include "atmosphere_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 1) uniform int u_order;
layout(location = 0) out vec4 o_density_r;
layout(location = 1) out vec4 o_density_m;
void main() {
  vec3 density_r, density_m;
  compute_density_texel(ivec3(ivec2(gl_FragCoord.xy), u_layer), u_order, density_r, density_m);
  o_density_r = vec4(density_r, 1.0);
  o_density_m = vec4(density_m, 1.0);
}
