// Uniform blocks, samplers and the four lookups cloud_functions.glsl needs, GLSL side.
// The C++ mirrors of the blocks are in include/cloudviewer/params.h (sizes static_asserted).
layout(std140, binding = 0) uniform CloudBlock { CloudParams u_cloud; };
layout(std140, binding = 1) uniform FrameBlock {
  mat4 u_inv_view_proj;  // camera-relative world <- clip
  mat4 u_view_proj;      // clip <- camera-relative world
  vec4 u_viewport;       // xy: full-resolution size in pixels; zw: bloom (half) size
  vec4 u_post;           // x: exposure; y: tone map operator; z: bloom strength; w: bloom threshold
};
layout(binding = 0) uniform sampler3D s_volume;     // RGBA32F: R base shape, G/B/A detail
layout(binding = 1) uniform sampler3D s_occupancy;  // R8: 1 where a coarse cell may hold density
layout(binding = 2) uniform sampler1D s_mie;        // R32F: Mie phase over theta in [0, pi]
layout(binding = 5) uniform sampler2D s_coverage;   // RG32F: layer coverage (R) and cloud type (G)

vec4 volume_texel(ivec3 texel) { return texelFetch(s_volume, texel, 0); }
vec4 volume_filtered(vec3 uvw) { return texture(s_volume, uvw); }
Number occupancy_texel(ivec3 cell) { return texelFetch(s_occupancy, cell, 0).r; }
Number mie_table_value(int i) { return texelFetch(s_mie, i, 0).r; }
vec2 coverage_texel(ivec2 texel) { return texelFetch(s_coverage, texel, 0).rg; }
ivec2 coverage_size() { return textureSize(s_coverage, 0); }
