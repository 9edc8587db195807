#version 450 core
// Precompute pass: the multiple-scattering LUT Psi_ms(r, mu_s) (CV_MS_LUT_SIZE^2, see
// atmosphere.glsl), one texel per fragment; reads the transmittance LUT of the pass before.
#include "atmosphere_headers.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = vec4(compute_multiple_scattering_texel(ivec2(gl_FragCoord.xy)), 1.0); }
