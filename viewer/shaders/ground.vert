#version 450 core
// Ground pass of the deferred pipeline (thesis 2.4.1). The mesh is uploaded once in units of the
// ground's half extent (a quad in box mode, a CV_GROUND_GRID^2 grid in layer mode); this stage
// scales it and, in layer mode, bends it onto the parabolic Earth (altitude 0 of layer_altitude:
// y = ground_y - (x^2 + z^2) / 2R), all camera-relative.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "cloud_params.glsl"
#include "frame_block.glsl"
layout(std140, binding = CV_BINDING_CLOUD) uniform CloudBlock { CloudParams u_cloud; };
layout(location = 0) in vec2 a_unit_xz;  // in [-1, 1]
out vec3 v_position;                     // camera-relative (m)
void main() {
  vec2 xz = a_unit_xz * u_cloud.ground_half_extent_m;
  float y = u_cloud.ground_y_m;
  if (u_cloud.layer_on > 0.5) y -= (xz.x * xz.x + xz.y * xz.y) / (2.0 * u_cloud.earth_radius_m);
  v_position = vec3(xz.x, y, xz.y);
  gl_Position = u_view_proj * vec4(v_position, 1.0);
}
