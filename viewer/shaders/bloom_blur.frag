#version 450 core
// Bloom step 2 (bloom_blur.glsl) at each fragment of the half-resolution target.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "post.glsl"
#include "bloom_blur.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = bloom_blur_pixel(ivec2(gl_FragCoord.xy)); }
