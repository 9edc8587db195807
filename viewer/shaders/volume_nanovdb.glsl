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
  TrilinearCell cell = trilinear_cell(uvw, n);
  ivec3 i0 = cell.i0;
  vec3 f = cell.f;
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

// render.skipping=tree (lighting.glsl tree_radius, march.glsl): the empty node of the density grid
// around volume voxel coordinates x (uvw * volume_dims; x and z wrapped into the tile for a tiling
// volume), from the includer's
//   int nanovdb_density_empty_dim(ivec3 ijk)   edge in voxels of the node holding ijk when that
//                                              node is a tile of value 0 or the background (8, 128
//                                              or 4096: a lower, upper or root tile), else 0
// (ijk in a leaf, or in a tile of another value). Every voxel of such a node reads 0. A trilinear
// lookup at x reads the corners floor(x - 0.5) and one more per axis, so where x lies at least half
// a voxel inside the node's faces all eight corners are the node's voxels and the density there is
// 0; `lo` and `hi` bound that box (0.01 voxel more inside: float positions of a few thousand voxels
// err by 1e-4 voxel). A tiling volume's node is cut at the tile's sides, where corners wrap. A
// point outside the volume on an axis that clamps looks up the edge voxel's node. False when x is
// not in such a box.
bool nanovdb_empty_box(vec3 x, OUT(vec3) lo, OUT(vec3) hi) {
  ivec3 n = ivec3(u_cloud.volume_dims);
  ivec3 texel = ivec3(clamp_index(int(floor(x.x)), n.x), clamp_index(int(floor(x.y)), n.y),
                      clamp_index(int(floor(x.z)), n.z));
  ivec3 ijk = texel + nanovdb_index_min();
  int dim = nanovdb_density_empty_dim(ijk);
  if (dim == 0) return false;
  ivec3 lower = ivec3(ijk.x & -dim, ijk.y & -dim, ijk.z & -dim) - nanovdb_index_min();  // dim: a power of 2
  ivec3 upper = lower + ivec3(dim);
  lo = vec3(lower) + vec3(0.51);
  hi = vec3(upper) - vec3(0.51);
  // Past a side that clamps (y; x and z unless the volume tiles) the density is 0, and a lookup
  // inside reads the edge voxel for every corner beyond it: a node holding that voxel reaches on.
  bool tiles = CV_MODE_TILES > 0.5;
  if (lower.y <= 0) lo.y = -1e30;
  if (upper.y >= n.y) hi.y = 1e30;
  if (tiles) {
    lo.x = max(lo.x, 0.51), lo.z = max(lo.z, 0.51);
    hi.x = min(hi.x, Number(n.x) - 0.51), hi.z = min(hi.z, Number(n.z) - 0.51);
  } else {
    if (lower.x <= 0) lo.x = -1e30;
    if (upper.x >= n.x) hi.x = 1e30;
    if (lower.z <= 0) lo.z = -1e30;
    if (upper.z >= n.z) hi.z = 1e30;
  }
  return x.x >= lo.x && x.y >= lo.y && x.z >= lo.z && x.x < hi.x && x.y < hi.y && x.z < hi.z;
}
