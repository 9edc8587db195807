// The primary ray march. The cloud math is split by concern into headers written once in the
// subset of GLSL that C++ also compiles (Bruneton & Neyret's functions.glsl / reference/functions.cc):
//   constants.glsl  mode codes, binding points, fixed sizes (also include/cloudviewer/constants.h)
//   common.glsl     hashing and jitter, index wrapping, ray intersections, pixel rays
//   phase.glsl      phase functions
//   cloud_type.glsl cloud-type height gradients (cloudgen/include/cloudgen, shared with cloudgen)
//   erosion.glsl    detail erosion and its bound (cloudgen, shared with its bake and the distance field)
//   medium.glsl     density, box and layer placement, occupancy
//   lighting.glsl   distance-field radius, Beer-Lambert, powder, step integration, light march and
//                   light volume, ground lighting
//   march.glsl      this file
//   sky.glsl        background sky and aerial perspective
//   compose.glsl    one pixel of the cloud pass: march, fade, debug outputs, background
//   post.glsl       tone mapping, sRGB, bloom taps and bilinear taps (the post passes need only this)
// The GL passes include them, in this order, after prelude_glsl.glsl, cloud_params.glsl and
// cloud_bindings.glsl; src/cpu_renderer.cpp includes the same files inside a C++ class with
// double-precision glm types. The including side provides the types Number/vec2/vec3/vec4/ivec2/
// ivec3/uint/mat4 and the IN/OUT macros (GLSL: prelude_glsl.glsl; C++: src/glsl_cpp.h, for every
// class that includes shader headers), `CloudParams u_cloud` and the lookups:
//   vec4   volume_texel(ivec3 texel)     texel of the RGBA volume, texel inside the grid
//   vec4   volume_filtered(vec3 uvw)     filtered lookup (the GPU's texture unit; exact on the CPU)
//   Number occupancy_texel(ivec3 cell)   1 where the coarse cell may hold density, else 0 (moving clouds in
//                                        box mode: the march box's grid, FrameSetup::moved_occupancy)
//   int    distance_texel(ivec3 cell)    L-infinity cells to the nearest cell holding density (0: it does)
//   Number light_volume_texel(ivec3 t)   optical depth toward the sun at a light-volume texel
//   Number light_volume_filtered(vec3 uvw)  its filtered lookup (exact on the CPU)
//   vec4 ms_volume_texel(ivec3 t)        multiply scattered fluence and 3 g x flux at a cell (render.ms_volume)
//   vec4 ms_volume_filtered(vec3 uvw)    its filtered lookup (exact on the CPU)
//   vec3 mie_table_value(int i)          i-th entry of the Mie phase table over theta in [0, pi], RGB
//   vec2   coverage_texel(ivec2 texel)   layer coverage map: R coverage, G cloud type, in [0, 1]
//   ivec2  coverage_size()               size of the coverage map in texels
//   vec3   motion_texel(int i, int row)  motion table D(h_i): row 0 this frame, row 1 the last (medium.glsl)
//   Number fine_detail_texel(ivec3 t)    render.detail's texture (fine_detail_size^3, repeats on every axis)
//   Number fine_detail_filtered(vec3 q)  its filtered lookup at q in tiles (GL_REPEAT; exact on the CPU)
// Constants are macros, not globals, so that the files also work inside a C++ class body.
//
// Implements R. Hogfeldt, "Convincing Cloud Rendering", and R. Olajos, "Real-Time Rendering of
// Volumetric Clouds", Lund University 2016 (seed 000): ray marching with a jittered start,
// occupancy skipping (large steps through empty coarse cells, step back one large step on entering
// an occupied cell, re-check after the small steps add up to one large step), adaptive step.

// Marches the camera ray along unit `rd` (camera at the origin) up to `t_scene` metres (scene depth).
// Returns (in-scattered radiance, transmittance). `iterations` counts loop trips (large or small);
// `t_mean` is the distance of the cloud weighted by opacity (for aerial perspective), 0 if none.
//
// Segments lie on the lattice t0 + n*dt (fixed step); the sample of each segment is at its start plus
// `jitter` times its length, so the jitter moves samples inside their segment and never changes the
// covered length: a uniform slab gives exactly exp(-sigma*d) for every jitter and step.
// Occupancy skipping moves by whole multiples of the small step (the large step is k small steps,
// just under the clearance the grid's padding proves: src/frame.cpp make_frame), so the samples it
// keeps are the very samples of the plain march and the image does not change; it only skips
// samples whose density is zero. Distance skipping jumps farther on the same lattice (as far as the
// distance field proves empty) and takes small steps with the thesis's re-check next to clouds.
// The density-aware step (density_step > 1) and the early exit (transmittance_cutoff) do change
// the image: they trade error for time (docs/viewer-speed.md).
vec4 march_clouds(vec3 rd, Number t_scene, Number jitter, OUT(int) iterations, OUT(Number) t_mean) {
  iterations = 0;
  t_mean = 0.0;
  Number t_weighted = 0.0;
  vec3 bmin = u_cloud.march_min_m;  // the box, grown by the motion's reach
  vec3 bmax = bmin + u_cloud.march_size_m;
  vec2 tb = layer_mode() ? shell_interval(vec3(0.0), rd) : ray_box(rd, bmin, bmax);
  Number t0 = tb.x;
  Number t1 = min(tb.y, min(t_scene, u_cloud.max_distance_m));
  vec3 radiance = vec3(0.0);
  Number transmittance = 1.0;
  if (!(t1 > t0)) return vec4(radiance, transmittance);

  Number dt = u_cloud.step_m;
  int k = max(int(u_cloud.large_step_count), 1);
  Number large = Number(k) * dt;
  bool adaptive = CV_MODE_ADAPTIVE > 0.5;
  bool skipping = CV_MODE_SKIP > 0.5;
  bool distance = skipping && CV_MODE_SKIP_DISTANCE > 0.5;
  int sparse = max(int(CV_MODE_DENSITY_STEP), 1);  // density-aware step: lattice steps per sparse step
  bool sparse_next = false;                        // the last sample was below density_step_below
  Number sigma_scale = u_cloud.sigma_t_per_m;
  Number albedo = u_cloud.albedo;
  vec3 phase0 = phase_function_rgb(dot(rd, u_cloud.sun_dir));
  vec3 phases = octave_phases(dot(rd, u_cloud.sun_dir));
  int max_iterations = int(u_cloud.max_iterations);

  bool large_mode = skipping;  // the last read of the coarse grid proved the space ahead empty
  bool check = skipping;       // read the coarse grid at this trip's position
  int n = 0;                   // small-step index on the fixed lattice
  Number t = t0;               // running distance for the adaptive march
  int since_check = 0;         // small steps since the coarse grid was last read
  for (int it = 0; it < max_iterations; ++it) {
    if (!adaptive) t = t0 + Number(n) * dt;
    if (t >= t1 || transmittance < u_cloud.transmittance_cutoff) break;
    iterations += 1;
    // One trip reads the coarse grid at most once and takes one sample at most: a trip either
    // jumps or samples. (SIMD hardware runs a branch that some lanes take for all of them: GPU warps
    // and llvmpipe's vector lanes alike. A loop body with a second read, or a jump path apart from
    // the sample path, costs every lane every trip.)
    bool jumped = false;
    if (check && !distance) {
      // Thesis: the coarse grid at the segment's start; one large step (k small steps, under the
      // padding's clearance) per empty cell. Entering an occupied cell from large steps, it steps
      // back one large step and takes small steps from there.
      since_check = 0;
      if (!occupied(rd * t)) {
        if (adaptive) t += large; else n += k;
        jumped = true;
      } else if (large_mode) {
        if (adaptive) t = max(t - large, t0); else n = max(n - k, 0);
        if (!adaptive) t = t0 + Number(n) * dt;
      }
      large_mode = jumped;
    }
    Number step_len = dt;
    if (adaptive) step_len = dt * (1.0 + u_cloud.adaptive_growth_per_m * max(t - u_cloud.adaptive_start_m, 0.0));
    int lattice_steps = sparse_next ? sparse : 1;
    step_len *= Number(lattice_steps);
    Number seg = min(step_len, t1 - t);
    vec3 p = rd * (t + jitter * seg);
    // The sample's motion and static volume coordinates serve the density and the field read alike.
    vec3 motion = motion_at(p);
    vec3 uvw = moving_uvw(p, motion);
    if (check && distance) {
      // Distance: the field is read at this trip's sample point. No point within r of it holds
      // density, so neither does this sample nor the next floor(0.999 r / dt) on the lattice (each a
      // whole step further along the unit ray; a shorter last segment only brings its sample closer).
      since_check = 0;
      // (render.skipping=tree: no point before the ray leaves the tree's empty node holds density.)
      Number r = CV_MODE_SKIP_TREE > 0.5 ? tree_exit_seen(uvw, rd) : empty_radius_of(empty_cells_seen(uvw));
      if (r > 0.0) {
        int jump = int(floor(0.999 * r / dt)) + 1;
        if (adaptive) t += Number(jump) * dt; else n += jump;
        jumped = true;
      }
      large_mode = jumped;
    }
    if (jumped) continue;
    Number density = cloud_density_seen(p, motion, uvw);
    if (density > 0.0) {
      Number sigma_t = density * sigma_scale;
      vec3 source = inscattered_radiance(p, rd, phase0, phases);
      radiance += transmittance * integrate_step(source, albedo * sigma_t, sigma_t, seg);
      Number step_transmittance = exp(-sigma_t * seg);
      t_weighted += transmittance * (1.0 - step_transmittance) * (t + jitter * seg);
      transmittance *= step_transmittance;
    }
    sparse_next = sparse > 1 && density < u_cloud.density_step_below;
    if (adaptive) t += step_len; else n += lattice_steps;
    // The small steps add up to one large step: read the coarse grid at the next trip. Distance
    // skipping reads it after every empty sample too (one integer fetch, cheaper than the density's
    // filtered one), so a gap between clouds is jumped as soon as it starts.
    since_check += lattice_steps;
    check = skipping && (since_check >= k || (distance && density <= 0.0));
  }
  if (transmittance < 1.0) t_mean = t_weighted / (1.0 - transmittance);
  return vec4(radiance, transmittance);
}
