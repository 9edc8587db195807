#version 450 core
// render.compute: cloud_sparse.glsl as a compute shader, one invocation per 4x4 block, its outputs
// stored as images.
#include "cloud_headers.glsl"
vec4 o_cloud;
vec4 o_depth;
vec4 o_air;      // ground: extinction per metre, 1 (all 0: the block has no ground)
vec4 o_air_e;    // ground: in-scattering per metre, 1 (all 0: no ground)
vec4 o_air_sky;  // sky: inscattered, 1 (all 0: the block has no sky)
#include "cloud_sparse.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_cloud;
layout(binding = CV_IMAGE_PASS_OUTPUT1, r32f) uniform writeonly image2D i_depth;
layout(binding = CV_IMAGE_PASS_OUTPUT2, rgba32f) uniform writeonly image2D i_air;
layout(binding = CV_IMAGE_PASS_OUTPUT3, rgba32f) uniform writeonly image2D i_air_e;
layout(binding = CV_IMAGE_PASS_OUTPUT4, rgba32f) uniform writeonly image2D i_air_sky;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(px, (ivec2(u_viewport.xy) + 3) / 4))) return;
  g_frag = vec2(px) + 0.5;
  sparse_main();
  imageStore(i_cloud, px, o_cloud);
  imageStore(i_depth, px, o_depth);
  imageStore(i_air, px, o_air);
  imageStore(i_air_e, px, o_air_e);
  imageStore(i_air_sky, px, o_air_sky);
}
