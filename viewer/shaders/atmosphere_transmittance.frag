#version 450 core
// Precompute pass: the transmittance LUT T(r, mu) to the top of the atmosphere, one texel per
// fragment (CV_TRANSMITTANCE_W x CV_TRANSMITTANCE_H, see atmosphere.glsl for the parametrisation).
#include "atmosphere_headers.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = vec4(compute_transmittance_texel(ivec2(gl_FragCoord.xy)), 1.0); }
