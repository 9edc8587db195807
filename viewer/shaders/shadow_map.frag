#version 450 core
// The ground shadow map (render.shadow_map): the clouds' transmittance toward the sun at the
// centres of a shadow_map_nx x shadow_map_nz grid of ground texels, with the march the ground
// pass would otherwise run per pixel (lighting.glsl; the CPU reference builds the same grid,
// build_shadow_map_cpu). One layer: the target is 3D so it is sized by the frame.
#include "cloud_headers.glsl"
layout(location = 0) uniform int u_layer;  // the 3D target's layer (always 0: one layer)
layout(location = 0) out float o_transmittance;
void main() {
  if (u_layer != 0) discard;
  o_transmittance = sun_shadow_transmittance(shadow_map_position(ivec2(gl_FragCoord.xy)));
}
