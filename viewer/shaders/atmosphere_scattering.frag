#version 450 core
// Precompute pass: Bruneton's 4D scattering LUT (atmosphere.glsl), one layer (an r texel) per
// draw, three parts per texel: single Rayleigh, single Mie and the orders 2..N, each before its
// phase function. Reads the transmittance and multiple-scattering LUTs of the passes before.
#include "atmosphere_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out vec4 o_rayleigh;
layout(location = 1) out vec4 o_mie;
layout(location = 2) out vec4 o_multiple;
void main() {
  vec3 rayleigh, mie, multiple;
  compute_scattering_texel(ivec3(ivec2(gl_FragCoord.xy), u_layer), rayleigh, mie, multiple);
  o_rayleigh = vec4(rayleigh, 1.0);
  o_mie = vec4(mie, 1.0);
  o_multiple = vec4(multiple, 1.0);
}
