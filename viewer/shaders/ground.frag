#version 450 core
// Ground pass: HDR radiance and the distance from the camera (the depth the cloud pass stops at).
#define CV_GROUND_PASS 1  // cloud_bindings.glsl: the shadow map is this pass's input
#include "cloud_headers.glsl"
in vec3 v_position;
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_distance;
void main() {
  o_color = vec4(ground_radiance(v_position), 1.0);
  o_distance = vec4(length(v_position), 0.0, 0.0, 0.0);
}
