// Cloud-type height gradients (A. Schneider, "The Real-Time Volumetric Cloudscapes of Horizon Zero
// Dawn", SIGGRAPH 2015): the density profile of stratus, cumulus and cumulonimbus over the
// normalised layer height h in [0, 1]. One definition, written in the subset of GLSL that C++ also
// compiles: cloudgen bakes the profiles into volumes (src/generate.cpp, through cloud_type.h) and
// the viewer's layer mode evaluates the same text on the GPU and in its CPU reference
// (viewer/shaders/medium.glsl), so a cumulus in the viewer is the cumulus cloudgen makes.
// Needs Number, smoothstep and mix from the including side.

// Rises over [b0, b1], falls over [t0, t1]; in [0, 1].
Number cloud_type_profile(Number h, Number b0, Number b1, Number t0, Number t1) {
  return smoothstep(b0, b1, h) * (1.0 - smoothstep(t0, t1, h));
}
Number stratus_gradient(Number h) { return cloud_type_profile(h, 0.0, 0.08, 0.15, 0.3); }
Number cumulus_gradient(Number h) { return cloud_type_profile(h, 0.0, 0.1, 0.4, 0.75); }
Number cumulonimbus_gradient(Number h) { return cloud_type_profile(h, 0.0, 0.08, 0.7, 1.0); }

// Continuous cloud type: 0 stratus, 0.5 cumulus, 1 cumulonimbus, linear in between. At exactly
// 0, 0.5 and 1 it returns the three profiles above bit for bit (mix with weight 0 or 1).
Number cloud_type_gradient(Number h, Number type) {
  if (type < 0.5) return mix(stratus_gradient(h), cumulus_gradient(h), type * 2.0);
  return mix(cumulus_gradient(h), cumulonimbus_gradient(h), type * 2.0 - 1.0);
}
