#version 450 core
// The camera's air LUT (render.air_lut, atmosphere.glsl): one distance slice per draw, two parts
// per texel (Rayleigh with the orders 2..N folded in, Mie), for this frame's camera altitude and
// sun. Reads the atmosphere's LUTs; the CPU reference computes the same texels as pixels read them.
#include "cloud_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out vec4 o_rayleigh;
layout(location = 1) out vec4 o_mie;
void main() {
  vec3 rayleigh, mie;
  frame_air_texel(ivec3(ivec2(gl_FragCoord.xy), u_layer), rayleigh, mie);
  o_rayleigh = vec4(rayleigh, 1.0);
  o_mie = vec4(mie, 1.0);
}
