#version 450 core
// render.compute: bloom step 2 (bloom_blur.glsl), one invocation per half-resolution pixel.
#include "prelude_glsl.glsl"
#include "constants.glsl"
#include "post.glsl"
#include "bloom_blur.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_color;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(px, textureSize(s_source, 0)))) return;
  imageStore(i_color, px, bloom_blur_pixel(px));
}
