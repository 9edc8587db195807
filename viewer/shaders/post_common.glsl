// Bilinear lookup done by hand (texel centres at (i + 0.5) / n, clamp to edge), the same
// arithmetic as the CPU post chain in src/cpu_renderer.cpp.
vec3 bilinear_fetch(sampler2D s, vec2 uv) {
  ivec2 n = textureSize(s, 0);
  vec2 x = uv * vec2(n) - 0.5;
  vec2 fl = floor(x);
  vec2 f = x - fl;
  ivec2 i0 = ivec2(fl);
  vec3 acc = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 i = clamp(i0 + o, ivec2(0), n - 1);
    vec2 w = mix(vec2(1.0) - f, f, vec2(o));
    acc += (w.x * w.y) * texelFetch(s, i, 0).rgb;
  }
  return acc;
}
