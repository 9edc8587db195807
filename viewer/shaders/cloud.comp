#version 450 core
// render.compute: the full cloud pass as a compute shader, one invocation per pixel in
// CV_COMPUTE_GROUP^2 groups, stored into the hdr target. The same pixel as cloud.frag's
// (cloud_pass.glsl); on GPUs that shade pixels on a fraction of their cores (NVIDIA's H100 and
// H200 run pixel shaders on two of their TPCs) compute work spreads over all of them.
#include "cloud_headers.glsl"
#include "cloud_pass.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_hdr;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= int(u_viewport.x) || px.y >= int(u_viewport.y)) return;
  imageStore(i_hdr, px, cloud_pass_pixel(px));
}
