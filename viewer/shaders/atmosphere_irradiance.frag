#version 450 core
// Precompute pass: the ground irradiance LUT E(mu_s) (CV_IRRADIANCE_W x 1, see atmosphere.glsl),
// one texel per fragment; reads the transmittance and multiple-scattering LUTs.
#include "atmosphere_headers.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = vec4(compute_irradiance_texel(int(gl_FragCoord.x)), 1.0); }
