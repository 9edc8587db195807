#version 450 core
// temporal_resolve.glsl at each fragment.
#include "cloud_headers.glsl"
layout(location = 0) out vec4 o_cloud;
layout(location = 1) out vec4 o_depth;
#include "temporal_resolve.glsl"
void main() {
  g_frag = gl_FragCoord.xy;
  resolve_main();
}
