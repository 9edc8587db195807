#version 450 core
// render.compute: temporal_resolve.glsl as a compute shader, one invocation per pixel, its
// outputs stored as images.
#include "cloud_headers.glsl"
vec4 o_cloud;
vec4 o_depth;
#include "temporal_resolve.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_cloud;
layout(binding = CV_IMAGE_PASS_OUTPUT1, r32f) uniform writeonly image2D i_depth;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(px, ivec2(u_viewport.xy)))) return;
  g_frag = vec2(px) + 0.5;
  resolve_main();
  imageStore(i_cloud, px, o_cloud);
  imageStore(i_depth, px, o_depth);
}
