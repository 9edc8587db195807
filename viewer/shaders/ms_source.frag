#version 450 core
// The multiple-scattering volume's inputs (render.ms_volume): one layer per draw of each coarse
// cell's mean extinction and first-scattering source (lighting.glsl ms_volume_source; the CPU
// reference computes the same cells). The renderer reads them back and solves the diffusion on
// the CPU (ms_diffusion.cpp), the same solver for both renderers.
#include "cloud_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out vec2 o_source;
void main() {
  o_source = ms_volume_source(ivec3(ivec2(gl_FragCoord.xy), u_layer));
}
