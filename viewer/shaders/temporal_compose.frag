#version 450 core
// temporal_compose.glsl at each fragment.
#include "cloud_headers.glsl"
layout(location = 0) out vec4 o_color;
#include "temporal_compose.glsl"
void main() {
  g_frag = gl_FragCoord.xy;
  compose_main();
}
