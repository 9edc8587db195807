// Detail erosion (A. Schneider, "The Real-Time Volumetric Cloudscapes of Horizon Zero Dawn",
// SIGGRAPH 2015, seed 001): the base shape R is eroded by the G/B/A detail fBm, wispy (the detail
// inverted) near the cloud base and billowy higher up. One definition, written in the subset of
// GLSL that C++ also compiles: the viewer's cloud_density (medium.glsl, GPU and CPU reference),
// cloudgen's baked VDB density (view.h eroded_density) and the viewer's eroded distance field
// (volume_prep.cpp, docs/viewer-speed.md) all read these lines.
// Needs Number, clamp, mix and max from the including side.

// The detail value of the three detail channels.
Number erosion_detail(Number g, Number b, Number a) { return 0.625 * g + 0.25 * b + 0.125 * a; }

// The erosion threshold at height fraction h (0 at the bottom of the cloud's layer or box, 1 at its
// top) of strength `erosion`: the detail inverted below h = 0.2, as it is above. Linear in the
// detail for a fixed h and monotonic in h, which is what lets the distance field bound it
// (erosion_bound).
Number erosion_threshold(Number detail, Number h, Number erosion) {
  return erosion * mix(1.0 - detail, detail, clamp(h * 5.0, 0.0, 1.0));
}

// The base after erosion by threshold e: positive exactly where base > e.
Number eroded_base(Number base, Number e) { return clamp((base - e) / max(1.0 - e, 1e-4), 0.0, 1.0); }

// An upper bound of base - e anywhere a texel (base, detail) takes part in a trilinear lookup seen
// at heights in [h0, h1]: base - threshold is linear in the texel's channels at a fixed height, so
// the filtered value is a convex combination of its texels' and never exceeds their largest; and
// it is monotonic in h, so its largest over the heights lies at one of the two ends. A cell whose
// texels all have a bound below 0 holds no density after erosion.
Number erosion_bound(Number base, Number detail, Number h0, Number h1, Number erosion) {
  return max(base - erosion_threshold(detail, h0, erosion), base - erosion_threshold(detail, h1, erosion));
}
