#version 450 core
// Full-screen cloud pass: cloud_pass.glsl's pixel at each fragment.
#include "cloud_headers.glsl"
#include "cloud_pass.glsl"
layout(location = 0) out vec4 o_color;
void main() { o_color = cloud_pass_pixel(ivec2(gl_FragCoord.xy)); }
