// HDR post (thesis 2.7): bloom bright pass and Gaussian taps, bilinear taps, tone mapping and sRGB
// encoding. Independent of the cloud block: the post passes include only constants.glsl and this
// file; the CPU reference includes it too. Needs the types and constants.glsl.

// Tone mapping of exposed linear radiance: Reinhard L/(1+L), ACES filmic (Narkowicz 2015), clamp.
vec3 tone_map(vec3 hdr, Number exposure, int op) {
  vec3 x = max(hdr * exposure, vec3(0.0));
  if (op == CV_TONEMAP_ACES) return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
  if (op == CV_TONEMAP_CLAMP) return clamp(x, 0.0, 1.0);
  return x / (vec3(1.0) + x);
}

Number srgb_encode_channel(Number c) {
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
vec3 srgb_encode(vec3 c) {
  return vec3(srgb_encode_channel(c.x), srgb_encode_channel(c.y), srgb_encode_channel(c.z));
}

// The display value of linear HDR radiance (bloom already added): expose, tone map, encode.
vec3 display_encode(vec3 hdr, Number exposure, int op) { return srgb_encode(tone_map(hdr, exposure, op)); }

// Bloom bright pass on the half-resolution image: what exceeds the threshold.
vec3 bloom_bright(vec3 c, Number threshold) { return max(c - vec3(threshold), vec3(0.0)); }

// Normalised weight of tap i in [-radius, radius] of a Gaussian with the given sigma (in texels).
Number gaussian_weight(int i, int radius, Number sigma) {
  Number sum = 0.0;
  for (int j = -radius; j <= radius; ++j) sum += exp(-Number(j * j) / (2.0 * sigma * sigma));
  return exp(-Number(i * i) / (2.0 * sigma * sigma)) / sum;
}

// Tap i in [-CV_BLOOM_RADIUS, CV_BLOOM_RADIUS] of the separable bloom blur of texel `pixel` along
// `direction` ((1,0) or (0,1)) in an image of `size` texels: the texel to read (clamped to the
// edge) and its weight.
Number bloom_tap(ivec2 pixel, ivec2 direction, int i, ivec2 size, OUT(ivec2) texel) {
  texel = clamp(pixel + direction * i, ivec2(0), size - 1);
  return gaussian_weight(i, CV_BLOOM_RADIUS, CV_BLOOM_SIGMA);
}

// Tap k in 0..3 of a bilinear lookup at uv (texel centres at (i + 0.5) / size, clamp to edge) in
// an image of `size` texels: the texel to read and its weight. The hand-made lookup keeps the GPU's
// post chain and the CPU's on the same arithmetic.
Number bilinear_tap(vec2 uv, ivec2 size, int k, OUT(ivec2) texel) {
  vec2 x = uv * vec2(size) - 0.5;
  vec2 fl = floor(x);
  vec2 f = x - fl;
  ivec2 o = ivec2(k & 1, k >> 1);
  texel = clamp(ivec2(fl) + o, ivec2(0), size - 1);
  vec2 w = mix(vec2(1.0) - f, f, vec2(o));
  return w.x * w.y;
}
