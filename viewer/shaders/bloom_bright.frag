#version 450 core
// Bloom step 1 (bloom_bright.glsl) at each fragment of the half-resolution target.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
#include "bloom_bright.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = bloom_bright_pixel(ivec2(gl_FragCoord.xy)); }
