// Bloom step 2, the pixel of both stages (bloom_blur.frag, and .comp with render.compute): one
// direction of the separable Gaussian blur at reduced resolution.
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_source;
layout(location = 0) uniform ivec2 u_direction;
vec4 bloom_blur_pixel(ivec2 px) {
  ivec2 n = textureSize(s_source, 0);
  vec3 acc = vec3(0.0);
  for (int i = -CV_BLOOM_RADIUS; i <= CV_BLOOM_RADIUS; ++i) {
    ivec2 q;
    Number w = bloom_tap(px, u_direction, i, n, q);
    acc += w * texelFetch(s_source, q, 0).rgb;
  }
  return vec4(acc, 1.0);
}
