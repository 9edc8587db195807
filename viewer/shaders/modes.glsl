// The frame's mode switches, read where the shaders branch on them. Here each CV_MODE_* is the
// uniform (or the test on it) it names: the CPU reference (cpu_renderer.cpp) and a GL program
// built with render.compiled_modes=false read them at run time. GlRenderer otherwise replaces this
// file's text with the frame's values as constants (kModes in gl_renderer.cpp: one row per macro;
// a macro missing there fails to compile) and keeps one set of programs per set of values, so the
// compiler drops every branch the frame does not take. llvmpipe runs both sides of a branch on a
// uniform (masked SIMD lanes), so an unused mode costs as if it were used: the thesis view from
// below took 6x longer with the generic program (docs/viewer-speed.md, "Compiled modes").
#define CV_MODE_LAYER u_cloud.layer_on
#define CV_MODE_MOTION u_cloud.motion_on
#define CV_MODE_TILES u_cloud.tiles_xz
#define CV_MODE_EXACT_FILTER u_cloud.exact_filter
#define CV_MODE_DETAIL u_cloud.has_detail
#define CV_MODE_CURL (u_cloud.curl_amplitude_m > 0.0 ? 1.0 : 0.0)
#define CV_MODE_FINE_DETAIL (u_cloud.fine_detail_strength > 0.0 ? 1.0 : 0.0)
#define CV_MODE_LIGHT u_cloud.light_mode
#define CV_MODE_DF_LIGHT u_cloud.df_light
#define CV_MODE_LIGHT_VOLUME u_cloud.light_volume_on
#define CV_MODE_SHADOW_MAP u_cloud.shadow_map_on
#define CV_MODE_MS_VOLUME u_cloud.ms_volume_on
#define CV_MODE_MS_OCTAVES u_cloud.ms_octaves
#define CV_MODE_PHASE u_cloud.phase_mode
#define CV_MODE_SKY u_cloud.sky_mode
#define CV_MODE_SKY_LUT u_cloud.sky_lut
#define CV_MODE_AIR_LUT u_cloud.air_lut
#define CV_MODE_OUTPUT u_cloud.output_mode
#define CV_MODE_ADAPTIVE u_cloud.adaptive
#define CV_MODE_SKIP u_cloud.occupancy_skip
#define CV_MODE_SKIP_DISTANCE u_cloud.skip_distance
#define CV_MODE_SKIP_TREE u_cloud.skip_tree
#define CV_MODE_DENSITY_STEP u_cloud.density_step
