#version 450 core
// Temporal upsampling, step 1 (seed 003): the cloud layer of one pixel per 4x4 block, the one the
// cross matrix picks for this frame (u_temporal.zw), into a quarter-by-quarter target: (radiance,
// transmittance) after aerial perspective, and the cloud's opacity-weighted distance (0: none)
// that the resolve reprojects with. With the precomputed sky also the air in front of the
// background at the same pixel (background_air; smooth, so temporal_compose upsamples it).
#include "cloud_headers.glsl"
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_scene_distance;
layout(location = 0) out vec4 o_cloud;
layout(location = 1) out vec4 o_depth;
layout(location = 2) out vec4 o_air;    // inscattered, scene distance
layout(location = 3) out vec4 o_air_t;  // transmittance to the scene
void main() {
  ivec2 full = ivec2(gl_FragCoord.xy) * 4 + ivec2(u_temporal.zw);
  full = min(full, ivec2(u_viewport.xy) - 1);  // a partial block at the right or top edge
  vec3 rd = pixel_ray(u_inv_view_proj, vec2(full) + 0.5, u_viewport.xy);
  float t_scene = texelFetch(s_scene_distance, full, 0).r;
  float t_mean = 0.0;
  int iterations = 0;
  o_cloud = cloud_layer(rd, full, t_scene, t_mean, iterations);
  o_depth = vec4(t_mean, 0.0, 0.0, 0.0);
  vec3 inscattered = vec3(0.0), transmittance = vec3(1.0);
  if (sky_precomputed()) background_air(rd, t_scene, inscattered, transmittance);
  o_air = vec4(inscattered, t_scene);
  o_air_t = vec4(transmittance, 0.0);
}
