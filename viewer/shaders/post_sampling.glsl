// GLSL-only: the bilinear lookup of post.glsl's taps over a sampler (the CPU reference runs the
// same taps over its buffers).
vec3 bilinear_fetch(sampler2D s, vec2 uv) {
  ivec2 n = textureSize(s, 0);
  vec3 acc = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 texel;
    Number w = bilinear_tap(uv, n, k, texel);
    acc += w * texelFetch(s, texel, 0).rgb;
  }
  return acc;
}
