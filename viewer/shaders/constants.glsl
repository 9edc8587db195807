// Constants shared by the GLSL passes and the C++ side (include/cloudviewer/constants.h includes
// this file): mode codes stored in CloudParams, texture and buffer binding points, fixed sizes.
// Macros, not globals, so the file works in GLSL, in C++ and inside the CPU reference's class body
// (Bruneton's constants.h pattern). Every number the two languages must agree on lives here.
#ifndef CV_CONSTANTS_GLSL
#define CV_CONSTANTS_GLSL

#define CV_PI 3.14159265358979323846

// Phase function (CloudParams.phase_mode; render.phase).
#define CV_PHASE_NONE 0
#define CV_PHASE_HG 1
#define CV_PHASE_MIE 2
#define CV_PHASE_TWO_LOBE_HG 3   // w HG(g) + (1 - w) HG(g2)
#define CV_PHASE_DRAINE_HG 4     // Jendersie & d'Eon 2023's HG + Draine fit of droplet diameter d
// Tone map operator (FrameBlock u_post.y; render.tonemap).
#define CV_TONEMAP_REINHARD 0
#define CV_TONEMAP_ACES 1
#define CV_TONEMAP_CLAMP 2
// What the cloud pass writes (CloudParams.output_mode; render.output).
#define CV_OUTPUT_RADIANCE 0
#define CV_OUTPUT_TRANSMITTANCE 1
#define CV_OUTPUT_ITERATIONS 2
// Light march (CloudParams.light_mode).
#define CV_LIGHT_OFF 0
#define CV_LIGHT_MARCH 1
#define CV_LIGHT_MARCH_SKIP_EMPTY 2
// Sky model (CloudParams.sky_mode; render.sky).
#define CV_SKY_ANALYTIC 0
#define CV_SKY_PRECOMPUTED 1

// Uniform buffer binding points.
#define CV_BINDING_CLOUD 0
#define CV_BINDING_FRAME 1
#define CV_BINDING_ATMOSPHERE 2
// Texture units. The two pass inputs are reused by every full-screen pass for its own sources.
#define CV_UNIT_VOLUME 0
#define CV_UNIT_OCCUPANCY 1
#define CV_UNIT_MIE 2
#define CV_UNIT_PASS_INPUT0 3
#define CV_UNIT_PASS_INPUT1 4
#define CV_UNIT_COVERAGE 5
#define CV_UNIT_TRANSMITTANCE 6
#define CV_UNIT_DISTANCE 7         // R8UI: the coarse grid's distance field (cells)
#define CV_UNIT_LIGHT_VOLUME 8     // R32F: optical depth toward the sun (render.light_volume)
#define CV_UNIT_PASS_INPUT2 9
#define CV_UNIT_PASS_INPUT3 10
#define CV_UNIT_MOTION 11
#define CV_UNIT_PASS_INPUT4 12
#define CV_UNIT_MULTIPLE_SCATTERING 13  // RGBA32F: the atmosphere's multiple-scattering LUT
// render.volume=nanovdb: the grids (a RGBA32UI buffer texture) and the leaf page table (RG32UI)
// of the density and first detail grid.
#define CV_UNIT_NANOVDB_GRIDS 14
// Shader storage buffer binding (its own namespace): the same grids when they fit a storage block.
#define CV_BINDING_NANOVDB 0
#define CV_UNIT_NANOVDB_PAGES 15
#define CV_UNIT_IRRADIANCE 16         // RGBA32F: the sky's irradiance on the ground (atmosphere LUT)
#define CV_UNIT_CURL 17               // RGBA32F: the curl field that distorts the detail lookup
// Image units (their own namespace): what a pass stores into with imageStore, in its table order.
#define CV_IMAGE_PASS_OUTPUT0 0
#define CV_IMAGE_PASS_OUTPUT1 1
#define CV_IMAGE_PASS_OUTPUT2 2
#define CV_IMAGE_PASS_OUTPUT3 3
#define CV_IMAGE_PASS_OUTPUT4 4
#define CV_COMPUTE_GROUP 8         // render.compute: a compute pass's work group is 8 x 8 pixels

// Fixed sizes.
#define CV_COVERAGE_MAP_SIZE 256   // layer-mode coverage map, texels per side
#define CV_MOTION_LUT_SIZE 1024    // motion displacement D(h) per frame, entries over h in [0, 1]
#define CV_MIE_TABLE_SIZE 1801     // Mie phase table entries over theta = 0..180 degrees (0.1 degree)
#define CV_GROUND_GRID 96          // ground cells per side in layer mode (curved Earth)
#define CV_BLOOM_RADIUS 6          // separable Gaussian bloom: taps on each side (half-resolution texels)
#define CV_BLOOM_SIGMA 3.0         // its standard deviation in texels
// Atmosphere (atmosphere.glsl): transmittance LUT size (mu x r, as Bruneton's demo) and the
// trapezoid intervals of its optical-depth integral.
#define CV_TRANSMITTANCE_W 256
#define CV_TRANSMITTANCE_H 64
#define CV_TRANSMITTANCE_SAMPLES 500
#define CV_SKY_SAMPLES 32           // per-pixel single-scattering samples along a view ray
// Multiple scattering LUT (Hillaire 2020): Psi_ms(h, mu_s), mu_s x altitude texels, each integrating
// over the sphere (sky bands + ground bands) x sectors directions with CV_MS_STEPS samples along each.
#define CV_MS_LUT_SIZE 32
#define CV_MS_SKY_BANDS 8
#define CV_MS_GROUND_BANDS 4
#define CV_MS_SECTORS 8
#define CV_MS_STEPS 20
// Ground irradiance LUT: the sky's irradiance E(mu_s) on the horizontal ground, CV_IRRADIANCE_W
// texels over mu_s in [-1, 1], each integrating the sky radiance over CV_IRRADIANCE_BANDS bands of
// cos(theta) x CV_IRRADIANCE_SECTORS sectors of phi in [0, pi] (counted twice).
#define CV_IRRADIANCE_W 64
#define CV_IRRADIANCE_BANDS 16
#define CV_IRRADIANCE_SECTORS 16
// Bruneton's 4D scattering LUT (r, mu, mu_s, nu), packed into a 3D texture of
// (CV_SCATTERING_NU x CV_SCATTERING_MU_S) x CV_SCATTERING_MU x CV_SCATTERING_R texels: his demo's
// 256 x 128 x 32 with twice the mu_s texels (512 x 128 x 32), which halves the error, most of it
// in twilight (single scattering RMS 1.6% -> 0.8%, docs/sky.md); mu_s below CV_SCATTERING_MU_S_MIN
// (the sun 102 degrees from the zenith, as his demo) collapses onto it.
#define CV_SCATTERING_NU 8
#define CV_SCATTERING_MU_S 64
#define CV_SCATTERING_MU 128
#define CV_SCATTERING_R 32
#define CV_SCATTERING_MU_S_MIN -0.2079
#define CV_UNIT_SCATTERING 18         // RGBA32F 3D: the scattering LUT's single Rayleigh part
#define CV_UNIT_SINGLE_MIE 19         // RGBA32F 3D: its single Mie part
#define CV_UNIT_SCATTERING_MULTIPLE 20  // RGBA32F 3D: its orders 2..N
#define CV_UNIT_MS_VOLUME 21          // RGBA32F 3D: the clouds' multiply scattered fluence and flux (render.ms_volume)
// atmosphere.density_orders: Bruneton's orders 2..N from scattering-density passes, in a smaller
// table of the same 4D parametrisation (the light scattered twice or more is smooth), 8 nu slices
// of CV_ORDERS_MU_S x CV_ORDERS_MU x CV_ORDERS_R texels; each density texel integrates the previous
// order's light over CV_DENSITY_THETA x 2 CV_DENSITY_THETA directions (Bruneton's 16 x 32), and
// each order is one CV_SKY_SAMPLES integral of the density along the texel's ray.
#define CV_ORDERS_MU_S 32
#define CV_ORDERS_MU 32
#define CV_ORDERS_R 16
#define CV_DENSITY_THETA 16
#define CV_UNIT_ORDERS_SINGLE_R 22    // RGBA32F 3D, orders table: single Rayleigh (the orders passes only)
#define CV_UNIT_ORDERS_SINGLE_M 23    // single Mie
#define CV_UNIT_ORDERS_DELTA 24       // the last order's scattered light
#define CV_UNIT_ORDERS_DENSITY 25     // the order's scattering density J (its Rayleigh part)
#define CV_UNIT_ORDERS_IRRADIANCE 26  // RGBA32F CV_IRRADIANCE_W x 1: the last order's irradiance on the ground
#define CV_UNIT_ORDERS_SUM 27         // RGBA32F 3D, orders table: the orders 2..N summed (read by the 4D LUT's pass)
#define CV_UNIT_ORDERS_DENSITY_M 28   // the density's Mie part
#define CV_UNIT_PASS_INPUT5 29       // a pass's sixth input (temporal_compose: the sky's air)
// The camera's air LUT (render.air_lut, atmosphere.glsl): the air's light seen from the camera's
// altitude with the frame's sun, over CV_AIR_AZIMUTH azimuths from the sun's (0..pi, both ends
// included) x CV_AIR_ELEVATION elevations (two halves, below and above the horizon, denser near
// it) x CV_AIR_DEPTH distances (0 to the longest ray, geometric with CV_AIR_DEPTH_LAMBDA), two
// parts: single Rayleigh with the orders 2..N folded in, single Mie, both before the phase functions.
#define CV_AIR_AZIMUTH 16
#define CV_AIR_ELEVATION 64
#define CV_AIR_DEPTH 64
#define CV_AIR_DEPTH_LAMBDA 9.0
#define CV_UNIT_AIR 30                // RGBA32F 3D: the air LUT's Rayleigh part (orders 2..N folded in)
#define CV_UNIT_AIR_MIE 31            // RGBA32F 3D: its Mie part
#define CV_UNIT_DETAIL 32             // R32F 3D, GL_REPEAT: the render-time detail texture (render.detail)
// Where the sky's integrals come from (atmosphere_sky's `source`).
#define CV_AIR_MARCH 0                // marched per pixel (scattering_sums)
#define CV_AIR_SKY_LUT 1              // Bruneton's 4D scattering LUT (render.sky_lut)
#define CV_AIR_CAMERA_LUT 2           // the camera's air LUT (render.air_lut)

// The multiple-scattering volume (render.ms_volume, lighting.glsl): each cell's extinction and
// first-scattering source are means over CV_MS_SUBSAMPLES^3 stratified points of the cell (2: as
// accurate against the path tracer as 4, docs/accuracy.md, at an eighth of the cost).
#define CV_MS_SUBSAMPLES 2

// Marching.
#define CV_TRANSMITTANCE_EPSILON 1e-3  // default render.transmittance_cutoff: stop marching below this
#define CV_NO_HIT 1e30                 // scene distance of a pixel that sees the sky
#define CV_NO_HIT_TEST 1e29            // t >= this means "no hit" (robust to float rounding of CV_NO_HIT)

#endif
