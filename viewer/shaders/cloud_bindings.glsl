// The cloud block, the samplers and the lookups the cloud headers need, GLSL side (the CPU
// reference defines the same lookups over its arrays in src/cpu_renderer.cpp).
layout(std140, binding = CV_BINDING_CLOUD) uniform CloudBlock { CloudParams u_cloud; };
layout(binding = CV_UNIT_VOLUME) uniform sampler3D s_volume;        // RGBA32F: R base shape, G/B/A detail
layout(binding = CV_UNIT_OCCUPANCY) uniform sampler3D s_occupancy;  // R8: 1 where a coarse cell may hold density
layout(binding = CV_UNIT_MIE) uniform sampler1D s_mie;              // RGB32F: Mie phase over theta in [0, pi] (650/550/450 nm)
layout(binding = CV_UNIT_COVERAGE) uniform sampler2D s_coverage;    // RG32F: layer coverage (R) and cloud type (G)

// render.volume=nanovdb: the NanoVDB float grids back to back in one buffer (byte offsets in
// u_nvdb_grid: density, then the three detail grids), read through PNanoVDB.h's GLSL mode (one
// read accessor per tree walk; volume_nanovdb.glsl filters). The buffer is a storage buffer, or
// an RGBA32UI buffer texture when the grids exceed a storage block (llvmpipe caps storage blocks
// at 128 MiB, buffer textures at 2^27 texels, 2 GiB; nanovdb_storage.glsl switches at compile
// time); PNANOVDB_BUF_CUSTOM lets the including side say how words are read.
// Plain uniforms, not CloudParams members: they describe the storage, not the look, and the CPU
// reference reads its own copy.
#include "nanovdb_storage.glsl"
#if CV_NANOVDB_BUFFER_TEXTURE
layout(binding = CV_UNIT_NANOVDB_GRIDS) uniform usamplerBuffer s_nvdb_grids;
#else
layout(std430, binding = CV_BINDING_NANOVDB) readonly buffer NanoVdbGrids { uint nvdb_words[]; };
#endif
#define PNANOVDB_GLSL
#define PNANOVDB_BUF_CUSTOM
struct pnanovdb_buf_t {
  uint unused;
};
uint pnanovdb_buf_read_uint32(pnanovdb_buf_t buf, uint byte_offset) {
  uint w = byte_offset >> 2u;
#if CV_NANOVDB_BUFFER_TEXTURE
  return texelFetch(s_nvdb_grids, int(w >> 2u))[w & 3u];
#else
  return nvdb_words[w];
#endif
}
uvec2 pnanovdb_buf_read_uint64(pnanovdb_buf_t buf, uint byte_offset) {
  return uvec2(pnanovdb_buf_read_uint32(buf, byte_offset), pnanovdb_buf_read_uint32(buf, byte_offset + 4u));
}
#define pnanovdb_grid_type_t uint
#define PNANOVDB_GRID_TYPE_GET(grid_typeIn, nameIn) pnanovdb_grid_type_constants[grid_typeIn].nameIn
#include "PNanoVDB.h"
uniform int u_nvdb_detail;      // 1: the three detail grids exist
uniform ivec3 u_nvdb_index_min; // grid index of the volume's voxel (0, 0, 0)
uniform uvec4 u_nvdb_grid;      // byte offsets of the density and detail grids in the buffer

uniform int u_nvdb_shared;      // 1: the detail grids share one layout (cloudgen's: one mask), so the
                                // address of a value in grid 1 plus the grids' offset is the value in 2, 3
uniform int u_nvdb_table;       // 1: find voxels through the leaf page table, 0: PNanoVDB's accessor
uniform ivec3 u_nvdb_page_origin; // grid index of the page table's first voxel (a multiple of 8)
// cloudgen::NanoPages of the density (R) and first detail grid (G): per 8^3 leaf cell the word
// index of the leaf's values, or 0x80000000 | the word index of the cell's one constant value.
layout(binding = CV_UNIT_NANOVDB_PAGES) uniform usampler3D s_nvdb_pages;

pnanovdb_readaccessor_t nvdb_acc[2];  // density, first detail grid
bool nvdb_ready = false;

pnanovdb_address_t nvdb_address(int grid, ivec3 ijk) {
  pnanovdb_buf_t buf;
  if (u_nvdb_table != 0) {
    uint e = texelFetch(s_nvdb_pages, (ijk - u_nvdb_page_origin) >> 3, 0)[grid];
    uint w = (e & 0x80000000u) != 0u ? (e & 0x7fffffffu)
                                     : e + uint(((ijk.x & 7) << 6) | ((ijk.y & 7) << 3) | (ijk.z & 7));
    pnanovdb_address_t a;
    a.byte_offset = w << 2u;
    return a;
  }
  if (!nvdb_ready) {
    for (int g = 0; g < 2; ++g) {
      pnanovdb_grid_handle_t h;
      h.address.byte_offset = u_nvdb_grid[g];
      pnanovdb_root_handle_t root = pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, h));
      pnanovdb_readaccessor_init(nvdb_acc[g], root);
    }
    nvdb_ready = true;
  }
  return pnanovdb_readaccessor_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, buf, nvdb_acc[grid], ijk);
}
Number nanovdb_density(ivec3 ijk) {
  pnanovdb_buf_t buf;
  return pnanovdb_read_float(buf, nvdb_address(0, ijk));
}
vec3 nanovdb_detail(ivec3 ijk) {
  pnanovdb_buf_t buf;
  pnanovdb_address_t a = nvdb_address(1, ijk);
  if (u_nvdb_shared != 0) {
    pnanovdb_address_t b = a, c = a;
    b.byte_offset += u_nvdb_grid.z - u_nvdb_grid.y;
    c.byte_offset += u_nvdb_grid.w - u_nvdb_grid.y;
    return vec3(pnanovdb_read_float(buf, a), pnanovdb_read_float(buf, b), pnanovdb_read_float(buf, c));
  }
  // Separate layouts: a root-to-leaf walk per grid (rare: files from elsewhere; the page table
  // is then off, see GlRenderer::set_volume).
  vec3 r;
  r.x = pnanovdb_read_float(buf, a);
  for (int g = 2; g < 4; ++g) {
    pnanovdb_grid_handle_t h;
    h.address.byte_offset = u_nvdb_grid[g];
    pnanovdb_root_handle_t root = pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, h));
    r[g - 1] = pnanovdb_read_float(buf, pnanovdb_root_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, buf, root, ijk));
  }
  return r;
}
// render.skipping=tree (volume_nanovdb.glsl nanovdb_empty_box): the edge of the density grid's
// node holding ijk when it is a tile of value <= 0 (read as 0) or the background, else 0. One walk
// from the root, whatever the lookups read through (the page table, the atlas): a read accessor's
// cache saves nothing on llvmpipe, which runs every branch of its cached/uncached paths.
int nanovdb_density_empty_dim(ivec3 ijk) {
  pnanovdb_buf_t buf;
  pnanovdb_grid_handle_t h;
  h.address.byte_offset = u_nvdb_grid.x;
  pnanovdb_root_handle_t root = pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, h));
  uint level = 0u;
  pnanovdb_address_t a = pnanovdb_root_get_value_address_and_level(PNANOVDB_GRID_TYPE_FLOAT, buf, root, ijk, level);
  if (level == 0u || pnanovdb_read_float(buf, a) > 0.0) return 0;
  return level == 1u ? 8 : level == 2u ? 128 : 4096;  // a lower, upper or root node's tile (or the background)
}
ivec3 nanovdb_index_min() { return u_nvdb_index_min; }
bool nanovdb_has_detail() { return u_nvdb_detail != 0; }
vec4 nanovdb_texel(ivec3 texel);    // volume_nanovdb.glsl
vec4 nanovdb_filtered(vec3 uvw);

// The storage is chosen at compile time (nanovdb_storage.glsl): a run-time branch here made
// llvmpipe's dense programs 4x slower and, at 512 steps with exact_filter, wrong.
#if CV_NANOVDB && CV_NANOVDB_ATLAS
// render.nanovdb_lookup=atlas (viewer/include/cloudviewer/scene.h NanoAtlas): s_volume holds the
// occupied bricks, s_nvdb_pages (RGBA16UI) per brick cell its first texel and 1, or 0 for none.
// A lookup whose lower corner is i0 reads cell (i0 + 1) >> 3, whose brick starts at texel 8 c - 1
// and holds all 8 corners; the texture unit filters inside the brick as it does the dense texture.
// Outside the box, the dense sampler's clamp (y; x, z unless the volume tiles) or wrap first.
vec3 atlas_position(vec3 uvw) {
  vec3 n = u_cloud.volume_dims;
  vec3 x = uvw * n - 0.5;
  vec3 hi = n - 1.0;
  if (CV_MODE_TILES > 0.5) {
    x.xz -= n.xz * floor(x.xz / n.xz);
    hi.xz = n.xz - 1.0 / 1024.0;
  }
  return clamp(x, vec3(-1.0), hi);
}
vec4 atlas_value(vec4 v) { return u_nvdb_detail != 0 ? v : vec4(v.x, 0.0, 0.0, 0.0); }
// The brick of the cell that holds lower corner i0, as the offset from a volume texel to its atlas
// texel (the brick's first texel - (8 c - 1)); false when the cell has no brick.
bool atlas_brick(ivec3 i0, out ivec3 offset) {
  ivec3 c = (i0 + 1) >> 3;
  uvec4 e = texelFetch(s_nvdb_pages, c, 0);
  offset = ivec3(e.xyz) + 1 - 8 * c;
  return e.w != 0u;
}
vec4 volume_texel(ivec3 texel) {
  ivec3 offset;
  return atlas_brick(texel, offset) ? atlas_value(texelFetch(s_volume, texel + offset, 0)) : vec4(0.0);
}
vec4 volume_filtered(vec3 uvw) {
  vec3 x = atlas_position(uvw);
  ivec3 offset;
  if (!atlas_brick(ivec3(floor(x)), offset)) return vec4(0.0);
  return atlas_value(texture(s_volume, (x + vec3(offset) + 0.5) / vec3(textureSize(s_volume, 0))));
}
#elif CV_NANOVDB
vec4 volume_texel(ivec3 texel) { return nanovdb_texel(texel); }
vec4 volume_filtered(vec3 uvw) { return nanovdb_filtered(uvw); }
#else
vec4 volume_texel(ivec3 texel) { return texelFetch(s_volume, texel, 0); }
vec4 volume_filtered(vec3 uvw) { return texture(s_volume, uvw); }
#endif
Number occupancy_texel(ivec3 cell) { return texelFetch(s_occupancy, cell, 0).r; }
vec3 mie_table_value(int i) { return texelFetch(s_mie, i, 0).rgb; }
vec2 coverage_texel(ivec2 texel) { return texelFetch(s_coverage, texel, 0).rg; }
layout(binding = CV_UNIT_MOTION) uniform sampler2D s_motion;        // RGBA32F: D(h) for this and the last frame
vec3 motion_texel(int i, int row) { return texelFetch(s_motion, ivec2(i, row), 0).xyz; }
layout(binding = CV_UNIT_CURL) uniform sampler3D s_curl;  // RGBA32F: the curl field (cloudgen/curl_distortion.glsl)
vec3 curl_texel(ivec3 i) { return texelFetch(s_curl, i, 0).xyz; }
layout(binding = CV_UNIT_DETAIL) uniform sampler3D s_detail;  // R32F, GL_REPEAT: render.detail's texture
Number fine_detail_texel(ivec3 i) { return texelFetch(s_detail, i, 0).r; }
Number fine_detail_filtered(vec3 q) { return texture(s_detail, q).r; }
ivec2 coverage_size() { return textureSize(s_coverage, 0); }
// Distance skipping and the light volume (march.glsl, lighting.glsl).
layout(binding = CV_UNIT_DISTANCE) uniform usampler3D s_distance;    // R8UI: cells to the nearest cell holding density
layout(binding = CV_UNIT_LIGHT_VOLUME) uniform sampler3D s_light_volume;  // R32F: optical depth toward the sun
int distance_texel(ivec3 cell) { return int(texelFetch(s_distance, cell, 0).r); }
Number light_volume_texel(ivec3 texel) { return texelFetch(s_light_volume, texel, 0).r; }
Number light_volume_filtered(vec3 uvw) { return texture(s_light_volume, uvw).r; }
// The ground shadow map (render.shadow_map): the ground pass's first input, an R32F 3D target of
// one layer; no other program reads it (ground_radiance runs in the ground pass alone).
#ifdef CV_GROUND_PASS
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler3D s_shadow_map;
Number shadow_map_texel(ivec2 texel) { return texelFetch(s_shadow_map, ivec3(texel, 0), 0).r; }
#else
Number shadow_map_texel(ivec2 texel) { return 1.0; }
#endif
layout(binding = CV_UNIT_MS_VOLUME) uniform sampler3D s_ms_volume;  // RGBA32F: fluence, 3 g x flux per unit sun irradiance
vec4 ms_volume_texel(ivec3 texel) { return texelFetch(s_ms_volume, texel, 0); }
vec4 ms_volume_filtered(vec3 uvw) { return texture(s_ms_volume, uvw); }
