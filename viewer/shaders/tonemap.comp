#version 450 core
// render.compute: the HDR resolve (tonemap.glsl), one invocation per pixel.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
#include "tonemap.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_display;
layout(binding = CV_IMAGE_PASS_OUTPUT1, rgba32f) uniform writeonly image2D i_linear;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= int(u_viewport.x) || px.y >= int(u_viewport.y)) return;
  vec4 display, linear;
  tonemap_pixel(px, display, linear);
  imageStore(i_display, px, display);
  imageStore(i_linear, px, linear);
}
