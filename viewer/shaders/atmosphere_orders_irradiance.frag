#version 450 core
// Precompute pass (atmosphere.density_orders): the ground irradiance of the light of order u_order
// (compute_orders_irradiance_texel), CV_IRRADIANCE_W x 1.
#define CV_ATMOSPHERE_ORDERS 1
#include "atmosphere_headers.glsl"
layout(location = 1) uniform int u_order;
layout(location = 0) out vec4 o_irradiance;
void main() { o_irradiance = vec4(compute_orders_irradiance_texel(int(gl_FragCoord.x), u_order), 1.0); }
