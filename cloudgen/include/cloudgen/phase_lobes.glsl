// Analytic phase lobes (per steradian, each integrating to 1 over the sphere), written once in the
// GLSL subset that C++ compiles too: cloudgen's `phase` command and tables (cloudgen/phase.h,
// double precision) and the viewer's shaders and CPU reference (viewer/shaders/phase.glsl) run these
// lines. c is the cosine of the scattering angle (1 = forward). Needs `Number`, sqrt and exp.
//   Henyey-Greenstein (1941); a two-lobe HG w HG(g1) + (1 - w) HG(g2); Draine (2003): HG times
//   (1 + alpha c^2) / (1 + alpha (1 + 2 g^2) / 3); Jendersie & d'Eon, "An Approximate Mie
//   Scattering Function for Fog and Cloud Rendering" (SIGGRAPH 2023): (1 - w_D) HG(g_HG) +
//   w_D Draine(g_D, alpha), its four parameters fitted as functions of the droplet diameter d in
//   [5, 50] um.

Number lobe_hg(Number g, Number c) {
  Number d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * 3.14159265358979323846 * d * sqrt(d));
}
Number lobe_two_hg(Number g1, Number g2, Number w, Number c) {
  return w * lobe_hg(g1, c) + (1.0 - w) * lobe_hg(g2, c);
}
Number lobe_draine(Number g, Number alpha, Number c) {
  return lobe_hg(g, c) * (1.0 + alpha * c * c) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0);
}
// The fit's parameters at droplet diameter d (um).
Number draine_fit_g_hg(Number d) { return exp(-0.0990567 / (d - 1.67154)); }
Number draine_fit_g_d(Number d) { return exp(-2.20679 / (d + 3.91029) - 0.428934); }
Number draine_fit_alpha(Number d) { return exp(3.62489 - 8.29288 / (d + 5.52825)); }
Number draine_fit_w_d(Number d) { return exp(-0.599085 / (d - 0.641583) - 0.665888); }
Number lobe_draine_hg(Number g_hg, Number g_d, Number alpha, Number w_d, Number c) {
  return (1.0 - w_d) * lobe_hg(g_hg, c) + w_d * lobe_draine(g_d, alpha, c);
}
