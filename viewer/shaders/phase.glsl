// Phase functions (1/sr), each integrating to 1 over the sphere: isotropic (the thesis's no-phase
// baseline), Henyey-Greenstein, and a tabulated Mie phase function (R. Hogfeldt, "Convincing Cloud
// Rendering", 2016). cos_theta is the cosine of the scattering angle between the light's direction
// of travel and the direction toward the viewer, so cos_theta = 1 is forward scattering: the viewer
// looking into the sun. Needs constants.glsl, cloudgen/phase_lobes.glsl (the analytic lobes shared
// with cloudgen), `u_cloud` and mie_table_value(i).

// Henyey-Greenstein; integrates to 1 over the sphere for |g| < 1.
Number phase_hg(Number cos_theta, Number g) {
  Number g2 = g * g;
  Number denom = 1.0 + g2 - 2.0 * g * cos_theta;
  return (1.0 - g2) / (4.0 * CV_PI * denom * sqrt(denom));
}

Number phase_isotropic() { return 1.0 / (4.0 * CV_PI); }

// Table over theta = 0..pi in `mie_table_size` equal steps, one value per colour channel (650,
// 550, 450 nm: the droplets' diffraction peak narrows and rises toward blue, the corona's colours),
// interpolated in log space (the forward peak is ~3e5 times the side value: linear interpolation
// would overshoot between the steep entries next to it), each channel already normalised to
// integrate to 1 over the sphere under this interpolant (src/mie.cpp). By hand on both sides so the
// GPU and the CPU agree to float precision.
vec3 phase_mie_rgb(Number cos_theta) {
  int n = int(u_cloud.mie_table_size);
  Number x = acos(clamp(cos_theta, -1.0, 1.0)) / CV_PI * Number(n - 1);
  int i = min(int(floor(x)), n - 2);
  Number f = x - Number(i);
  vec3 a = log(max(mie_table_value(i), vec3(1e-30)));
  vec3 b = log(max(mie_table_value(i + 1), vec3(1e-30)));
  return exp(mix(a, b, vec3(f)));
}

// The phase function of one channel-less quantity (the path tracer's sampling, the light octaves):
// the Mie table's green channel, or the analytic lobe.
Number phase_function(Number cos_theta) {
  int mode = int(CV_MODE_PHASE);
  if (mode == CV_PHASE_HG) return phase_hg(cos_theta, u_cloud.hg_g);
  if (mode == CV_PHASE_MIE) return phase_mie_rgb(cos_theta).y;
  if (mode == CV_PHASE_TWO_LOBE_HG) return lobe_two_hg(u_cloud.hg_g, u_cloud.hg_g2, u_cloud.lobe_weight, cos_theta);
  if (mode == CV_PHASE_DRAINE_HG)
    return lobe_draine_hg(u_cloud.draine_g_hg, u_cloud.draine_g_d, u_cloud.draine_alpha, u_cloud.draine_w_d, cos_theta);
  return phase_isotropic();
}

// The phase function per colour channel: the Mie table's three, or the analytic lobe in all three.
vec3 phase_function_rgb(Number cos_theta) {
  if (int(CV_MODE_PHASE) == CV_PHASE_MIE) return phase_mie_rgb(cos_theta);
  return vec3(phase_function(cos_theta));
}
