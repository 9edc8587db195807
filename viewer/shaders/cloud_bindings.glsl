// The cloud block, the samplers and the lookups the cloud headers need, GLSL side (the CPU
// reference defines the same lookups over its arrays in src/cpu_renderer.cpp).
layout(std140, binding = CV_BINDING_CLOUD) uniform CloudBlock { CloudParams u_cloud; };
layout(binding = CV_UNIT_VOLUME) uniform sampler3D s_volume;        // RGBA32F: R base shape, G/B/A detail
layout(binding = CV_UNIT_OCCUPANCY) uniform sampler3D s_occupancy;  // R8: 1 where a coarse cell may hold density
layout(binding = CV_UNIT_MIE) uniform sampler1D s_mie;              // R32F: Mie phase over theta in [0, pi]
layout(binding = CV_UNIT_COVERAGE) uniform sampler2D s_coverage;    // RG32F: layer coverage (R) and cloud type (G)

vec4 volume_texel(ivec3 texel) { return texelFetch(s_volume, texel, 0); }
vec4 volume_filtered(vec3 uvw) { return texture(s_volume, uvw); }
Number occupancy_texel(ivec3 cell) { return texelFetch(s_occupancy, cell, 0).r; }
Number mie_table_value(int i) { return texelFetch(s_mie, i, 0).r; }
vec2 coverage_texel(ivec2 texel) { return texelFetch(s_coverage, texel, 0).rg; }
layout(binding = CV_UNIT_MOTION) uniform sampler2D s_motion;        // RGBA32F: D(h) for this and the last frame
vec3 motion_texel(int i, int row) { return texelFetch(s_motion, ivec2(i, row), 0).xyz; }
ivec2 coverage_size() { return textureSize(s_coverage, 0); }
// Distance skipping and the light volume (march.glsl, lighting.glsl).
layout(binding = CV_UNIT_DISTANCE) uniform usampler3D s_distance;    // R8UI: cells to the nearest cell holding density
layout(binding = CV_UNIT_LIGHT_VOLUME) uniform sampler3D s_light_volume;  // R32F: optical depth toward the sun
int distance_texel(ivec3 cell) { return int(texelFetch(s_distance, cell, 0).r); }
Number light_volume_texel(ivec3 texel) { return texelFetch(s_light_volume, texel, 0).r; }
Number light_volume_filtered(vec3 uvw) { return texture(s_light_volume, uvw).r; }
