// render.volume=nanovdb: the volume lookups over NanoVDB grids, in the GLSL subset C++ also
// compiles (the GPU reads the grids through PNanoVDB.h's GLSL mode, the CPU reference through its
// C mode). Needs common.glsl, `u_cloud` and, from the including side:
//   Number nanovdb_density(ivec3 ijk)          value of the density grid at index ijk
//   vec3   nanovdb_detail(ivec3 ijk)           values of the three detail grids at index ijk
//   ivec3  nanovdb_index_min()                 grid index of the volume's voxel (0, 0, 0)
//   bool   nanovdb_has_detail()                the three detail grids exist
// The grids hold 0 in every inactive voxel and tile (cloudgen zeroes them on load), so a lookup
// returns exactly the dense texture's texel: same values, same filter, same image.

// The texel the dense RGBA texture holds at `texel` (density clamped at 0, as prepare_volume).
vec4 nanovdb_texel(ivec3 texel) {
  ivec3 ijk = texel + nanovdb_index_min();
  Number d = max(nanovdb_density(ijk), 0.0);
  if (!nanovdb_has_detail()) return vec4(d, 0.0, 0.0, 0.0);
  return vec4(d, nanovdb_detail(ijk));
}

// medium.glsl's volume_trilinear (same corners, weights and order of sums, so the same bits),
// reading the eight densities first: where all are 0 the density is 0 and the detail, which only
// erodes density > 0, is never read (three quarters of the lookups in empty space saved).
vec4 nanovdb_filtered(vec3 uvw) {
  ivec3 n = ivec3(u_cloud.volume_dims);
  bool tiles = CV_MODE_TILES > 0.5;
  vec3 x = uvw * vec3(n) - 0.5;
  vec3 fl = floor(x);
  vec3 f = x - fl;
  ivec3 i0 = ivec3(fl);
  ivec3 corner[8];
  Number dens[8];
  bool any = false;
  for (int k = 0; k < 8; ++k) {
    corner[k] = trilinear_corner(i0, k, n, tiles);
    dens[k] = max(nanovdb_density(corner[k] + nanovdb_index_min()), 0.0);
    any = any || dens[k] > 0.0;
  }
  if (!any) return vec4(0.0);
  bool detail = nanovdb_has_detail();
  vec4 acc = vec4(0.0);
  for (int k = 0; k < 8; ++k) {
    vec4 t = detail ? vec4(dens[k], nanovdb_detail(corner[k] + nanovdb_index_min())) : vec4(dens[k], 0.0, 0.0, 0.0);
    acc += trilinear_weight(f, k) * t;
  }
  return acc;
}
