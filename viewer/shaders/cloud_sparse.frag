#version 450 core
// cloud_sparse.glsl at each fragment.
#include "cloud_headers.glsl"
layout(location = 0) out vec4 o_cloud;
layout(location = 1) out vec4 o_depth;
layout(location = 2) out vec4 o_air;      // ground: extinction per metre, 1 (all 0: the block has no ground)
layout(location = 3) out vec4 o_air_e;    // ground: in-scattering per metre, 1 (all 0: no ground)
layout(location = 4) out vec4 o_air_sky;  // sky: inscattered, 1 (all 0: the block has no sky)
#include "cloud_sparse.glsl"
void main() {
  g_frag = gl_FragCoord.xy;
  sparse_main();
}
