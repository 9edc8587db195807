#version 450 core
// The light volume (render.light_volume): one layer per draw of the sun's optical depth at the
// texel centres of a light_volume_dims grid over the box, with the same light march the per-sample
// lighting uses, where a cloud sample can read it (lighting.glsl light_volume_value; the CPU
// reference builds the same grid, build_light_volume_cpu).
#include "cloud_headers.glsl"
layout(location = 0) uniform int u_layer;
layout(location = 0) out float o_tau;
void main() {
  o_tau = light_volume_value(ivec3(ivec2(gl_FragCoord.xy), u_layer));
}
