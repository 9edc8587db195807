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
vec3 transmittance_filtered(vec2 uv) { return texture(s_transmittance, uv).rgb; }  // GL_LINEAR, clamped
vec3 multiple_scattering_texel(ivec2 texel) { return texelFetch(s_multiple_scattering, texel, 0).rgb; }
vec3 irradiance_texel(int texel) { return texelFetch(s_irradiance, ivec2(texel, 0), 0).rgb; }
vec3 scattering_texel(ivec3 texel) { return texelFetch(s_scattering, texel, 0).rgb; }
vec3 single_mie_texel(ivec3 texel) { return texelFetch(s_single_mie, texel, 0).rgb; }
vec3 scattering_multiple_texel(ivec3 texel) { return texelFetch(s_scattering_multiple, texel, 0).rgb; }
layout(binding = CV_UNIT_AIR) uniform sampler3D s_air_lut;          // RGBA32F, the camera's air LUT (render.air_lut)
layout(binding = CV_UNIT_AIR_MIE) uniform sampler3D s_air_lut_mie;  // RGBA32F, its Mie part
vec3 air_texel(int part, ivec3 texel) { return part == 0 ? texelFetch(s_air_lut, texel, 0).rgb : texelFetch(s_air_lut_mie, texel, 0).rgb; }
layout(binding = CV_UNIT_ORDERS_SUM) uniform sampler3D s_orders_sum;  // RGBA32F, the orders table
// The orders table (atmosphere.density_orders), parts 0..5: single Rayleigh, single Mie, the last
// order's light, the density's Rayleigh and (5) Mie angular integrals, the sum. Only the orders passes (CV_ATMOSPHERE_ORDERS) read the
// first four and the last order's ground irradiance.
#ifdef CV_ATMOSPHERE_ORDERS
layout(binding = CV_UNIT_ORDERS_SINGLE_R) uniform sampler3D s_orders_single_r;
layout(binding = CV_UNIT_ORDERS_SINGLE_M) uniform sampler3D s_orders_single_m;
layout(binding = CV_UNIT_ORDERS_DELTA) uniform sampler3D s_orders_delta;
layout(binding = CV_UNIT_ORDERS_DENSITY) uniform sampler3D s_orders_density;
layout(binding = CV_UNIT_ORDERS_DENSITY_M) uniform sampler3D s_orders_density_m;
layout(binding = CV_UNIT_ORDERS_IRRADIANCE) uniform sampler2D s_orders_irradiance;
vec3 orders_texel(int part, ivec3 t) {
  if (part == 0) return texelFetch(s_orders_single_r, t, 0).rgb;
  if (part == 1) return texelFetch(s_orders_single_m, t, 0).rgb;
  if (part == 2) return texelFetch(s_orders_delta, t, 0).rgb;
  if (part == 3) return texelFetch(s_orders_density, t, 0).rgb;
  if (part == 5) return texelFetch(s_orders_density_m, t, 0).rgb;
  return texelFetch(s_orders_sum, t, 0).rgb;
}
vec3 orders_irradiance_texel(int t) { return texelFetch(s_orders_irradiance, ivec2(t, 0), 0).rgb; }
#else
vec3 orders_texel(int part, ivec3 t) { return part == 4 ? texelFetch(s_orders_sum, t, 0).rgb : vec3(0.0); }
vec3 orders_irradiance_texel(int t) { return vec3(0.0); }
#endif
