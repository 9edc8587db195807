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
