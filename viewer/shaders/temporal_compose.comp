#version 450 core
// render.compute: temporal_compose.glsl as a compute shader, one invocation per pixel, its
// outputs stored as images.
#include "cloud_headers.glsl"
vec4 o_color;
#include "temporal_compose.glsl"
layout(local_size_x = CV_COMPUTE_GROUP, local_size_y = CV_COMPUTE_GROUP) in;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_color;
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(px, ivec2(u_viewport.xy)))) return;
  g_frag = vec2(px) + 0.5;
  compose_main();
  imageStore(i_color, px, o_color);
}
