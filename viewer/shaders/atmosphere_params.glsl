// AtmosphereParams: the std140 uniform block of the atmosphere passes (binding
// CV_BINDING_ATMOSPHERE), shared with C++ exactly as cloud_params.glsl is: include/cloudviewer/
// atmosphere.h includes it twice (float for the GPU block, double for the CPU reference). Members
// come in 16-byte groups (a vec3 and one scalar, or four scalars). A constituent the user turned
// off (atmosphere.rayleigh=false, ...) has its coefficients set to 0 on the C++ side, so the
// shaders need no switches. Lengths in metres, coefficients per metre.
struct AtmosphereParams {
  vec3 rayleigh_scattering_per_m; Number bottom_radius_m;          // planet radius (the ground)
  vec3 mie_scattering_per_m;      Number top_radius_m;             // top of the atmosphere
  vec3 mie_extinction_per_m;      Number rayleigh_scale_height_m;  // exp(-h / H) density profiles
  vec3 ozone_absorption_per_m;    Number mie_scale_height_m;
  vec3 ground_albedo;             Number mie_g;                    // Cornette-Shanks asymmetry
  Number ozone_bottom_m;          // tent profile: 0 below, 1 at the peak, 0 above the top
  Number ozone_peak_m;
  Number ozone_top_m;
  Number sun_angular_radius;      // radians
  Number scattering_orders;       // 1 = single scattering only; N > 1 adds orders 2..N (Psi_ms series)
  Number density_orders;          // 1: with the 4D LUT, orders 2..N from Bruneton's scattering-density passes
  Number reserved1;
  Number reserved2;
};
