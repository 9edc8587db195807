// Shared helpers of every cloud header: hashing and jitter, index wrapping, ray-box and ray-parabola
// intersection. Written in the subset of GLSL that C++ also compiles (see march.glsl's header for
// the pattern); needs constants.glsl and the types Number/vec2/vec3/vec4/ivec2/ivec3/uint.

// PCG hash (Jarzynski & Olano 2020) on unsigned 32-bit integers: wraps identically in GLSL and C++.
uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Jitter of the first sample in [0, 1), per pixel (GL window coordinates) and per frame.
// 24 bits so the value is exact in float and double.
Number jitter_offset(ivec2 pixel, int frame) {
  uint h = pcg_hash(uint(pixel.x) + pcg_hash(uint(pixel.y) + pcg_hash(uint(frame))));
  return Number(h >> 8u) / 16777216.0;
}

// GLSL leaves % undefined for negative operands (C++ truncates): keep both operands non-negative.
// i mod n in [0, n), without an integer division: SIMD hardware has none (llvmpipe runs one per
// lane), and the exact filters and the layer's coverage lookup wrap texels per sample. The float quotient's floor is off by at most one
// (|i| < 2^22), which the two selects correct, so the result is exact.
int wrap_index(int i, int n) {
  int r = i - n * int(floor(Number(i) / Number(n)));
  return r < 0 ? r + n : (r >= n ? r - n : r);
}
int clamp_index(int i, int n) { return min(max(i, 0), n - 1); }

// Corner k (0..7, x fastest) of a trilinear lookup whose lower corner is i0, over n texels: wrapped
// in x and z when `tiles` (GL_REPEAT), clamped otherwise and always in y (GL_CLAMP_TO_EDGE); and
// its weight for the fraction f. The volume, light-volume and NanoVDB filters share these, so their
// corners, weights and order of sums are the same.
ivec3 trilinear_corner(ivec3 i0, int k, ivec3 n, bool tiles) {
  ivec3 i = i0 + ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  i.x = tiles ? wrap_index(i.x, n.x) : clamp_index(i.x, n.x);
  i.y = clamp_index(i.y, n.y);
  i.z = tiles ? wrap_index(i.z, n.z) : clamp_index(i.z, n.z);
  return i;
}
Number trilinear_weight(vec3 f, int k) {
  vec3 w = mix(vec3(1.0) - f, f, vec3(ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1)));
  return w.x * w.y * w.z;
}
// The lower corner i0 and the fractions f of a trilinear lookup at uvw (0..1 over n texels, texel
// centres at (i + 0.5) / n): the set-up every hand-written filter shares with the texture unit.
struct TrilinearCell {
  ivec3 i0;
  vec3 f;
};
TrilinearCell trilinear_cell(vec3 uvw, ivec3 n) {
  vec3 x = uvw * vec3(n) - 0.5;
  vec3 fl = floor(x);
  TrilinearCell c;
  c.i0 = ivec3(fl);
  c.f = x - fl;
  return c;
}

// Entry and exit distances of a ray from the origin along unit `rd` through the box [bmin, bmax];
// entry clamped to 0 (camera inside). No hit when x >= y.
vec2 ray_box(vec3 rd, vec3 bmin, vec3 bmax) {
  vec3 inv = 1.0 / rd;
  vec3 ta = bmin * inv;
  vec3 tb = bmax * inv;
  vec3 tmin = min(ta, tb);
  vec3 tmax = max(ta, tb);
  Number t_near = max(max(tmin.x, tmin.y), tmin.z);
  Number t_far = min(min(tmax.x, tmax.y), tmax.z);
  return vec2(max(t_near, 0.0), t_far);
}

// Roots of a t^2 + b t + c = 0 (a >= 0), sorted; (1e30, -1e30) when there are none.
// The stable form (q = -(b + sign(b) sqrt(D)) / 2; roots c/q and q/a) avoids cancellation.
vec2 parabola_roots(Number a, Number b, Number c) {
  Number aa = max(a, 1e-12);
  Number disc = b * b - 4.0 * aa * c;
  if (disc < 0.0) return vec2(1e30, -1e30);
  Number s = sqrt(disc);
  Number q = -0.5 * (b + (b >= 0.0 ? s : -s));
  Number r1 = q != 0.0 ? c / q : 0.0;
  Number r2 = q / aa;
  return vec2(min(r1, r2), max(r1, r2));
}

// World ray direction (camera-relative, unit) through a pixel: `frag` in window coordinates
// (pixel centres at i + 0.5), `viewport` the image size in pixels, OpenGL clip conventions.
vec3 pixel_ray(mat4 inv_view_proj, vec2 frag, vec2 viewport) {
  vec2 ndc = frag / viewport * 2.0 - 1.0;
  vec4 near_point = inv_view_proj * vec4(ndc, -1.0, 1.0);
  return normalize(vec3(near_point) / near_point.w);
}
