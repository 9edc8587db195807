// Temporal upsampling (seed 003, "Research on Real-time Cloud Movement Based on Flow-map and
// Temporal Upsampling", 2023): every frame marches one pixel of each 4x4 block, in the order of
// the cross matrix M = [[0,8,2,10],[12,4,14,6],[3,11,1,9],[15,7,13,5]] (row y, column x), so a
// block is covered in 16 frames and neighbouring frames land far apart. Written in the GLSL subset
// C++ also compiles: the renderer picks each frame's offset with it, the tests check the order.

// M[y][x], the frame (mod 16) at which block position (x, y) is marched. Packed as 4-bit entries,
// row-major, x fastest: rows 0-1 in the first word, rows 2-3 in the second.
int cross_matrix(int x, int y) {
  int i = (y & 3) * 4 + (x & 3);
  uint word = i < 8 ? 0x6E4CA280u : 0x5D7F91B3u;
  return int((word >> uint(4 * (i & 7))) & 15u);
}

// Position inside the 4x4 block that frame `frame` marches.
ivec2 cross_matrix_offset(int frame) {
  int k = frame & 15;
  ivec2 r = ivec2(0, 0);
  for (int i = 0; i < 16; ++i)
    if (cross_matrix(i & 3, i >> 2) == k) r = ivec2(i & 3, i >> 2);
  return r;
}

// The air in front of the ground as the sparse pixels pass it on to the others (cloud_sparse.frag
// writes it, temporal_compose.frag upsamples it): the air along a ray is taken as uniform, with
// extinction `s` (per metre) and in-scattered light per metre `e`, so that toward a point at
// distance t the transmittance is T = exp(-s t) and the in-scattered light I = e (1 - T) / s
// (e t where s t -> 0). Exact for a uniform medium, nearly so between rays 4 pixels apart, and
// linear in (s, e): the compose filters them bilinearly and evaluates once per pixel.
// (1 - exp(-x)) / x per channel, with its series where x is small.
vec3 air_fraction(vec3 x) {
  return mix(vec3(1.0) - 0.5 * x, (vec3(1.0) - exp(-x)) / max(x, vec3(1e-30)), step(vec3(1e-4), x));
}
// (s, e) from the air at one pixel: in-scattered light and transmittance toward distance t > 0.
void air_coefficients(vec3 inscattered, vec3 transmittance, Number t, OUT(vec3) s, OUT(vec3) e) {
  s = -log(max(transmittance, vec3(1e-30))) / t;
  e = inscattered / (t * air_fraction(s * t));
}
// The air toward distance t from (s, e).
void air_over_distance(vec3 s, vec3 e, Number t, OUT(vec3) inscattered, OUT(vec3) transmittance) {
  transmittance = exp(-s * t);
  inscattered = e * t * air_fraction(s * t);
}
