// CloudParams: the std140 uniform block of the cloud, ground and shadow passes, shared with C++.
// The C++ side includes this file twice (Number = float for the GPU block, double for the CPU
// reference; see include/cloudviewer/params.h, which static_asserts both sizes, and the test that
// compares every member's offset with the driver's std140 offsets). Layout rule that makes std140
// and the tight C++ layout agree: members come in groups of 16 bytes, either a vec3 followed by one
// scalar or four scalars (a vec3 must never follow a vec3, nor a vec2 a single scalar). Counts,
// flags and mode codes are stored as Number too (exact up to 2^24). Positions are relative to the
// camera, in metres, so a camera kilometres from the origin keeps float precision. Units are in
// the names: _m metres, _per_m per metre.
struct CloudParams {
  // The volume (box mode; layer mode uses the counts, the flags and occ_*).
  vec3 volume_min_m;  Number voxel_size_m;     // min corner relative to the camera
  vec3 volume_size_m; Number tiles_xz;         // extent; tiles_xz: 1 when x and z wrap
  vec3 volume_dims;   Number has_detail;       // voxel counts; 1 when G/B/A detail is present
  vec3 occ_dims;      Number occ_cell_voxels;  // coarse occupancy cells; cell edge in voxels
  // Light.
  vec3 sun_dir;       Number sun_radiance;     // unit vector toward the sun; sun radiance scale
  vec3 sun_color;     Number ambient_scale;    // sun colour; ambient radiance scale
  vec3 ambient_color; Number albedo;           // ambient (sky) colour; single-scattering albedo
  // Medium.
  Number sigma_t_per_m;     // extinction at density 1
  Number erosion;           // detail erosion strength [0, 1]
  Number density_scale;     // density multiplier
  Number powder_c;          // c of the powder term 1 - exp(-c tau)
  // Primary march.
  Number step_m;            // small step
  Number large_step_count;  // small steps per large (occupancy) step, an integer >= 1
  Number max_distance_m;
  Number max_iterations;
  Number adaptive;          // 1: step grows with distance
  Number adaptive_start_m;
  Number adaptive_growth_per_m;
  Number occupancy_skip;    // 1: large steps through empty coarse cells
  // Light march and phase.
  Number light_mode;        // CV_LIGHT_*
  Number light_samples;
  Number light_step_m;      // first light step
  Number light_growth;      // each light step is this many times the previous
  Number phase_mode;        // CV_PHASE_*
  Number hg_g;              // Henyey-Greenstein asymmetry
  Number mie_table_size;    // entries of the Mie table
  Number powder_strength;   // [0, 1]
  // Control.
  Number jitter;            // 1: jittered sample inside each step
  Number frame_index;       // jitter pattern
  Number exact_filter;      // 1: trilinear by hand from texelFetch
  Number output_mode;       // CV_OUTPUT_*
  // Distance skipping, early exit, density-aware step, light volume (docs/viewer-speed.md).
  vec3 light_volume_dims;   Number light_volume_on;  // texels of the optical-depth volume; 1: look tau up
  Number skip_distance;     // 1: large steps as long as the distance field allows (with occupancy_skip)
  Number df_cell_m;         // coarse cell edge in world metres (the smallest per axis)
  Number df_margin_m;       // half a voxel: how far trilinear density reaches past a non-empty cell
  Number df_light;          // 1: the light and shadow marches skip samples the field proves empty
  Number transmittance_cutoff;  // stop the primary march below this transmittance
  Number density_step;      // small steps per step after a sample below density_step_below (1: off)
  Number density_step_below;
  Number sky_lut;           // 1: the sky and the aerial perspective from the 4D scattering LUT (render.sky_lut)
  // Ground and sky.
  Number ground_y_m;        // ground height relative to the camera
  Number ground_albedo;
  Number ground_on;
  Number ground_half_extent_m;
  vec3 camera_world_mod_m;  Number shadow_samples;   // camera position modulo 1024 m (ground pattern phase)
  vec3 sky_zenith;          Number sun_disc_scale;   // zenith sky radiance; sun disc radiance scale
  // Layer mode (the tileable texture repeated over a spherical shell; parabolic Earth, see
  // layer_altitude): horizontal offsets already reduced modulo their period.
  Number layer_on;
  Number layer_bottom_m;    // altitudes above the ground
  Number layer_top_m;
  Number earth_radius_m;
  Number camera_altitude_m; // camera altitude above the ground
  Number camera_tile_x_m;   // camera x, z modulo the tile
  Number camera_tile_z_m;
  Number coverage_period_m; // the coverage map repeats over this distance
  Number tile_x_m;          // tile size in x and z
  Number tile_z_m;
  Number camera_coverage_x_m;  // camera x, z modulo the coverage period
  Number camera_coverage_z_m;
  Number coverage_bias;     // added to the coverage map
  Number cloud_type;        // 0 stratus .. 1 cumulonimbus; -1 = from the map
  Number sky_mode;          // CV_SKY_*
  Number sky_altitude_m;    // camera altitude above the ground for the atmosphere (both modes)
  // Motion (cloudgen/motion.glsl): what is seen at p is the static volume at p - D(h, time_s).
  // Box mode marches the box grown by the motion's reach at this time (march_*; = the box when still).
  vec3 march_min_m;         Number time_s;     // seconds
  vec3 march_size_m;        Number motion_on;  // 1 when the clouds move (time != 0 and motion_moves)
  Number wind_dir_x;        // unit wind direction in x-z
  Number wind_dir_z;
  Number wind_speed_mps;
  Number wind_shear;
  Number flow_speed_hz;
  Number flow_up_m;
  Number flow_forward_m;
  Number curl_shift;        // curl distortion (cloudgen/curl_distortion.glsl): the field's rise, in its tiles
  Number height_min_m;      // box mode: the box heights are measured in (motion, erosion), min y
  Number height_size_m;     //   relative to the camera, and its height
  Number air_lut;           // 1: the sky and the aerial perspective from the camera's air LUT (render.air_lut)
  Number motion_stretch;    // >= 1: how much faster the static point seen at p moves than p along a ray (make_frame)
  // Multiple scattering by octaves (lighting.glsl inscattered_radiance).
  Number ms_octaves;        // 1 = single scattering only, up to 4
  Number ms_attenuation;    // a: octave weight factor
  Number ms_extinction;     // b: optical depth factor
  Number ms_eccentricity;   // c: phase eccentricity factor
  // Ambient light from below (render.sky=precomputed: the ground and the air under the camera's
  // horizon; the analytic sky: = ambient_color). lighting.glsl mixes it with ambient_color by height.
  vec3 ambient_below_color; Number ambient_pad;
  // Analytic phase lobes (cloudgen/phase_lobes.glsl): two-lobe HG and the HG + Draine fit's
  // parameters (computed on the host from render.droplet_diameter).
  Number hg_g2;             // two-lobe-hg: backward lobe asymmetry
  Number lobe_weight;       // two-lobe-hg: forward lobe weight
  Number draine_g_hg;       // draine-hg: the HG lobe's asymmetry
  Number draine_g_d;        // draine-hg: the Draine lobe's asymmetry
  Number draine_alpha;      // draine-hg: Draine's alpha
  Number draine_w_d;        // draine-hg: the Draine lobe's weight
  Number phase_pad0;
  Number phase_pad1;
  // Curl-noise distortion of the detail lookup (motion.curl_*; cloudgen/curl_distortion.glsl).
  vec3 curl_repeats;        Number curl_amplitude_m;  // whole tiles of the field per volume axis; 0 = off
  // Multiple scattering from the flux-limited diffusion solve (render.ms_volume, lighting.glsl).
  vec3 ms_volume_dims;      Number ms_volume_on;      // cells of the fluence volume; 1: orders >= 2 from it
  // Moving clouds in box mode: occupied() reads the march box's own grid for this time (cells of
  // moved_occ_cell_m metres from march_min_m; FrameSetup::moved_occupancy), no motion lookup.
  vec3 moved_occ_dims;      Number moved_occ_cell_m;
  // Ground shadow map (render.shadow_map, box mode; lighting.glsl ground_shadow): the clouds'
  // transmittance toward the sun at the centres of shadow_map_nx x shadow_map_nz ground texels of
  // shadow_map_texel_m, from (shadow_map_min_x_m, shadow_map_min_z_m) relative to march_min_m: the
  // part of the ground whose sun rays cross the march box.
  Number shadow_map_on;     // 1: the ground pass looks its shadow up instead of marching it per pixel
  Number shadow_map_nx;
  Number shadow_map_nz;
  Number shadow_map_texel_m;
  Number shadow_map_min_x_m;
  Number shadow_map_min_z_m;
  Number shadow_map_ground_m;  // the ground's height in the march box (rounded to 1 mm: part of the map's key)
  Number skip_tree;         // 1: with skip_distance, the radius from the NanoVDB tree's empty nodes, not the field
  // Render-time detail (render.detail, medium.glsl fine_detail_threshold): a small tileable Worley
  // texture laid over the box (or the repeating texture) a whole number of times per axis, eroding
  // the density near its boundary. Erosion only: it never adds density, so skipping stays exact.
  vec3 fine_detail_repeats; Number fine_detail_strength;  // tiles per volume axis; strength, 0 = off
  Number fine_detail_size;  // texture edge in texels (detail_texture.h)
  Number fine_detail_pad0;
  Number fine_detail_pad1;
  Number fine_detail_pad2;
};
