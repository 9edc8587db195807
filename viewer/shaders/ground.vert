#version 450 core
// Ground pass of the deferred pipeline (thesis 2.4.1): a large quad in camera-relative coordinates.
#include "prelude_glsl.glsl"
#include "cloud_params.glsl"
#include "bindings.glsl"
layout(location = 0) in vec3 a_position;  // camera-relative (m)
out vec3 v_position;
void main() {
  v_position = a_position;
  gl_Position = u_view_proj * vec4(a_position, 1.0);
}
