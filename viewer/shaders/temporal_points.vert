#version 450 core
// Temporal upsampling when nothing moved since the last frame: one point per pixel marched this
// frame (the pixel 4 (i, j) + u_temporal.zw of quarter texel (i, j), gl_VertexID = j * quarter
// width + i), so the held frame's passes touch those pixels only and every other pixel keeps
// last frame's value in place. A point of GL's default size 1 centred on a pixel centre covers
// that pixel alone; the points of partial blocks past the right or top edge fall outside the
// viewport.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
void main() {
  int quarter_w = (int(u_viewport.x) + 3) / 4;  // cloud_quarter's width (rounded up)
  ivec2 q = ivec2(gl_VertexID % quarter_w, gl_VertexID / quarter_w);
  vec2 px = vec2(q * 4 + ivec2(u_temporal.zw)) + 0.5;
  gl_Position = vec4(px / u_viewport.xy * 2.0 - 1.0, 0.0, 1.0);
}
