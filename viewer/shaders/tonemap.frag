#version 450 core
// HDR resolve (tonemap.glsl) at each fragment: the display image and the linear HDR frame.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
#include "tonemap.glsl"
layout(location = 0) out vec4 o_display;
layout(location = 1) out vec4 o_linear;
void main() { tonemap_pixel(ivec2(gl_FragCoord.xy), o_display, o_linear); }
