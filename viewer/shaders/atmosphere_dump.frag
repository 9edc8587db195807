#version 450 core
// Reads the transmittance LUT back through transmittance_to_top (the lookup the shaders use) on a
// grid: x over mu in [-1, 1] (u_grid.x values), y over altitude 0..top (u_grid.y values); rays that
// hit the ground hold 0 (cloudviewer --dump-lut transmittance).
#include "atmosphere_headers.glsl"
layout(location = 0) uniform ivec2 u_grid;
layout(location = 0) out vec4 o_color;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  Number mu = -1.0 + 2.0 * Number(px.x) / Number(u_grid.x - 1);
  Number h = (u_atmo.top_radius_m - u_atmo.bottom_radius_m) * Number(px.y) / Number(u_grid.y - 1);
  Number r = u_atmo.bottom_radius_m + h;
  o_color = ray_intersects_ground(r, mu) ? vec4(0.0) : vec4(transmittance_to_top(r, mu), 1.0);
}
