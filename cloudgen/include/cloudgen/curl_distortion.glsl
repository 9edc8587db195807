// Curl-noise distortion of the detail lookup (seed 003's motion list; Schneider 2015, "The
// real-time volumetric cloudscapes of Horizon Zero Dawn": curl noise distorts the detail noise,
// most at the bottoms of clouds, so they churn). One definition in the GLSL subset that C++ also
// compiles: the viewer's medium.glsl (GPU and CPU reference) and cloudgen's sequence bake
// (cloudgen/src/sequence.cpp) shift the detail lookup by curl_detail_offset_m.
// Needs Number, ivec3, vec3, floor, clamp, mix and curl_texel(ivec3) (the field's texel: each
// component in [-1, 1], cloudgen/motion.h curl_field_texels) from the including side.

#define CV_CURL_SIZE 32

int curl_wrap(int i) { return i >= 0 ? i % CV_CURL_SIZE : (CV_CURL_SIZE - 1) - ((-i - 1) % CV_CURL_SIZE); }

// The curl field at q, in units of its tile (it repeats with period 1 on every axis), trilinear
// between texel centres; each component in [-1, 1].
vec3 curl_field(vec3 q) {
  vec3 x = q * Number(CV_CURL_SIZE) - 0.5;
  vec3 fl = floor(x);
  vec3 f = x - fl;
  ivec3 i0 = ivec3(fl);
  vec3 acc = vec3(0.0);
  for (int k = 0; k < 8; ++k) {
    ivec3 b = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    vec3 w = mix(vec3(1.0) - f, f, vec3(b));
    ivec3 i = i0 + b;
    acc += (w.x * w.y * w.z) * curl_texel(ivec3(curl_wrap(i.x), curl_wrap(i.y), curl_wrap(i.z)));
  }
  return acc;
}

// The detail lookup's offset in metres for a sample whose static volume coordinates are uvw (0..1
// over the box or the repeating texture), seen at height fraction seen_h: the field laid over the
// volume `repeats` times per axis (whole numbers, so a tiling volume stays seamless), risen by
// `shift` of its tiles (motion.curl_rise * t), scaled by amplitude_m and by 1 - h (strongest at
// the base, none at the top). Zero when amplitude_m is 0.
vec3 curl_detail_offset_m(vec3 uvw, Number seen_h, vec3 repeats, Number shift, Number amplitude_m) {
  if (amplitude_m <= 0.0) return vec3(0.0);
  vec3 q = uvw * repeats - vec3(0.0, shift, 0.0);
  return curl_field(q) * (amplitude_m * (1.0 - clamp(seen_h, 0.0, 1.0)));
}
