// Temporal upsampling when nothing moved since the last frame (the camera, the clouds, the
// settings; gl_renderer.cpp runs this pass then, and cloud_sparse.frag, temporal_resolve.frag and
// temporal_compose.frag otherwise). Only this frame's pixel of each 4x4 block (the cross matrix's,
// u_temporal.zw) changes: it is marched as cloud_sparse.frag marches it, composed over the
// background as the full cloud pass composes it (compose_over), and stored straight into last
// frame's resolved layer and composed image, which render() keeps in place. Every other pixel
// keeps last frame's values, so after 16 held frames each pixel holds its own march and its own
// air, as in the full render. One invocation per block: the held frame's cloud work is 1/16 of the
// pixels', with no full-resolution pass of its own. Both stages call held_block: the fragment
// stage (cloud_sparse_held.frag) and, with render.compute, the compute stage (.comp).
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_scene_distance;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_color;
layout(binding = CV_IMAGE_PASS_OUTPUT0, rgba32f) uniform writeonly image2D i_layer;    // full: (L, T)
layout(binding = CV_IMAGE_PASS_OUTPUT1, r32f) uniform writeonly image2D i_layer_depth;  // full: cloud distance
layout(binding = CV_IMAGE_PASS_OUTPUT2, rgba32f) uniform writeonly image2D i_hdr;      // full: composed HDR
// Block `block`'s pixel of this frame: marched, stored into the three full-resolution images, and
// returned as the quarter target's two values (as cloud_sparse.frag writes them).
void held_block(ivec2 block, out vec4 cloud, out vec4 depth) {
  ivec2 full = block * 4 + ivec2(u_temporal.zw);
  cloud = vec4(0.0, 0.0, 0.0, 1.0);
  depth = vec4(0.0);
  if (full.x >= int(u_viewport.x) || full.y >= int(u_viewport.y)) return;  // a partial block without this frame's pixel
  vec3 rd = pixel_ray(u_inv_view_proj, vec2(full) + 0.5, u_viewport.xy);
  float t_scene = texelFetch(s_scene_distance, full, 0).r;
  float t_mean = 0.0;
  int iterations = 0;
  cloud = cloud_layer(rd, full, t_scene, t_mean, iterations);
  depth = vec4(t_mean, 0.0, 0.0, 0.0);
  imageStore(i_layer, full, cloud);
  imageStore(i_layer_depth, full, depth);
  imageStore(i_hdr, full, vec4(compose_over(cloud, rd, t_scene, texelFetch(s_scene_color, full, 0).rgb), 1.0));
}
