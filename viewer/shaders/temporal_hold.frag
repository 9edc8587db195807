#version 450 core
// Temporal upsampling, step 2 when nothing moved since the last frame (the camera, the clouds, the
// settings; gl_renderer.cpp picks this pass then, temporal_resolve.frag otherwise): a pixel marched
// this frame takes its fresh value, every other pixel last frame's, as temporal_resolve does in
// that case. A program of its own because llvmpipe runs every branch of a shader whatever a
// uniform says: in the resolve, the reprojection and the neighbourhood clamp made a held frame
// cost about 2.7x this pass's time (3.6 against 1.3 ms at 320x180 on llvmpipe; docs/motion.md).
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_fresh;          // quarter: (L, T)
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_fresh_depth;    // quarter: cloud distance
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_history;        // full, last frame: (L, T)
layout(binding = CV_UNIT_PASS_INPUT3) uniform sampler2D s_history_depth;  // full, last frame: distance
layout(location = 0) out vec4 o_cloud;
layout(location = 1) out vec4 o_depth;

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  ivec2 off = ivec2(u_temporal.zw);
  if ((px.x & 3) == off.x && (px.y & 3) == off.y) {  // marched this frame
    o_cloud = texelFetch(s_fresh, px >> 2, 0);
    o_depth = texelFetch(s_fresh_depth, px >> 2, 0);
  } else {
    o_cloud = texelFetch(s_history, px, 0);
    o_depth = texelFetch(s_history_depth, px, 0);
  }
}
