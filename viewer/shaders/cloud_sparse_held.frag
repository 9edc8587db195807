#version 450 core
// The held temporal frame (cloud_sparse_held.glsl) at one fragment per 4x4 block.
#include "cloud_headers.glsl"
#include "cloud_sparse_held.glsl"
layout(location = 0) out vec4 o_cloud;  // the quarter target's, as cloud_sparse.frag writes them
layout(location = 1) out vec4 o_depth;
void main() { held_block(ivec2(gl_FragCoord.xy), o_cloud, o_depth); }
