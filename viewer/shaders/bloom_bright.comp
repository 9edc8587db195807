#version 450 core
// render.compute: bloom step 1 (bloom_bright.glsl), one invocation per half-resolution pixel.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "frame_block.glsl"
#include "post.glsl"
#include "post_sampling.glsl"
#include "bloom_bright.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_color;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= int(u_viewport.z) || px.y >= int(u_viewport.w)) return;
  imageStore(i_color, px, bloom_bright_pixel(px));
}
