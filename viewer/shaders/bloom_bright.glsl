// Bloom step 1 (thesis 2.7), the pixel of both stages (bloom_bright.frag, and .comp with
// render.compute): the HDR frame downsampled to half resolution, what is brighter than the threshold.
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_hdr;
vec4 bloom_bright_pixel(ivec2 px) {
  vec3 c = bilinear_fetch(s_hdr, (vec2(px) + 0.5) / u_viewport.zw);
  return vec4(bloom_bright(c, u_post.w), 1.0);
}
