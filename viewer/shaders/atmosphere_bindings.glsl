// The atmosphere block and LUT samplers, GLSL side (the CPU reference defines the same lookups
// over its arrays in src/atmosphere.cpp).
layout(std140, binding = CV_BINDING_ATMOSPHERE) uniform AtmosphereBlock { AtmosphereParams u_atmo; };
layout(binding = CV_UNIT_TRANSMITTANCE) uniform sampler2D s_transmittance;  // RGBA32F, CV_TRANSMITTANCE_W x _H
layout(binding = CV_UNIT_MULTIPLE_SCATTERING) uniform sampler2D s_multiple_scattering;  // RGBA32F, CV_MS_LUT_SIZE^2

layout(binding = CV_UNIT_IRRADIANCE) uniform sampler2D s_irradiance;  // RGBA32F, CV_IRRADIANCE_W x 1
layout(binding = CV_UNIT_SCATTERING) uniform sampler3D s_scattering;  // RGBA32F, the 4D LUT packed
layout(binding = CV_UNIT_SINGLE_MIE) uniform sampler3D s_single_mie;  // RGBA32F, the same layout
layout(binding = CV_UNIT_SCATTERING_MULTIPLE) uniform sampler3D s_scattering_multiple;  // RGBA32F, the same

vec3 transmittance_texel(ivec2 texel) { return texelFetch(s_transmittance, texel, 0).rgb; }
vec3 multiple_scattering_texel(ivec2 texel) { return texelFetch(s_multiple_scattering, texel, 0).rgb; }
vec3 irradiance_texel(int texel) { return texelFetch(s_irradiance, ivec2(texel, 0), 0).rgb; }
vec3 scattering_texel(ivec3 texel) { return texelFetch(s_scattering, texel, 0).rgb; }
vec3 single_mie_texel(ivec3 texel) { return texelFetch(s_single_mie, texel, 0).rgb; }
vec3 scattering_multiple_texel(ivec3 texel) { return texelFetch(s_scattering_multiple, texel, 0).rgb; }
