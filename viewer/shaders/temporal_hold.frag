#version 450 core
// Temporal upsampling, step 2 when nothing moved since the last frame (the camera, the clouds, the
// settings; gl_renderer.cpp picks this pass then, temporal_resolve.frag otherwise): drawn as one
// point per pixel marched this frame (temporal_points.vert) into last frame's resolved layer,
// kept in place, so that pixel takes its fresh value and every other pixel keeps last frame's,
// as temporal_resolve does in that case, at 1/16 of the pixels' cost (docs/motion.md).
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_fresh;        // quarter: (L, T)
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_fresh_depth;  // quarter: cloud distance
layout(location = 0) out vec4 o_cloud;
layout(location = 1) out vec4 o_depth;

void main() {
  ivec2 q = ivec2(gl_FragCoord.xy) >> 2;
  o_cloud = texelFetch(s_fresh, q, 0);
  o_depth = texelFetch(s_fresh_depth, q, 0);
}
