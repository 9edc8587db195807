#version 450 core
// render.compute: the held temporal frame (cloud_sparse_held.glsl) as a compute shader, one
// invocation per 4x4 block, the quarter target's two values stored as images too.
#include "cloud_headers.glsl"
#include "cloud_sparse_held.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT3, rgba32f) uniform writeonly image2D i_quarter;
layout(binding = CV_IMAGE_PASS_OUTPUT4, r32f) uniform writeonly image2D i_quarter_depth;
void main() {
  ivec2 block = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(block, (ivec2(u_viewport.xy) + 3) / 4))) return;
  vec4 cloud, depth;
  held_block(block, cloud, depth);
  imageStore(i_quarter, block, cloud);
  imageStore(i_quarter_depth, block, depth);
}
