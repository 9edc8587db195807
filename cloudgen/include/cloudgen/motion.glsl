// Cloud motion (seed 003, "Research on Real-time Cloud Movement Based on Flow-map and Temporal
// Upsampling", 2023): wind with height shear plus the two-phase flow map. One definition, written
// in the subset of GLSL that C++ also compiles: the viewer's medium.glsl displaces every density
// lookup by motion_displacement (on the GPU and in its CPU reference) and cloudgen bakes the same
// displacement into VDB sequences (cloudgen/motion.h), so a baked frame is the viewer's frame.
// Needs Number, vec2, vec3, fract, sin, cos, abs, mix, clamp from the including side.
//
// Convention: what is seen at position p and time t is the static volume at p - D(h, t), where h is
// the height fraction of p in the cloud layer (or box) and D is the displacement below, in metres.
// D(h, 0) = 0 exactly, so time 0 is the static volume bit for bit.

#define CV_MOTION_TWO_PI 6.283185307179586

// Unit wind direction in the x-z plane from an azimuth in degrees, measured like the sun's:
// clockwise from -z (0 blows toward -z, 90 toward +x).
vec2 wind_direction_xz(Number azimuth_deg) {
  Number a = azimuth_deg * (CV_MOTION_TWO_PI / 360.0);
  return vec2(sin(a), -cos(a));
}

// The procedural flow map: the curl of a smooth 2D stream function psi(u, v) made of three waves,
// periodic in u (the flow phase) with period 1. Returns (up, forward) in [-1, 1], what a flow
// texture holds after the seed's `texture * 2 - 1` (each component is normalised by the sum of its
// waves' amplitude-frequency products, so it can never leave [-1, 1]).
vec2 procedural_flow(vec2 uv) {
  Number du = 0.0;  // d psi / du
  Number dv = 0.0;  // d psi / dv
  // wave k: amplitude a, integer frequency m in u (periodic), frequency n in v, phase c
  Number a0 = 1.0;  Number m0 = 1.0; Number n0 = 0.8; Number c0 = 0.3;
  Number a1 = 0.5;  Number m1 = 2.0; Number n1 = 1.7; Number c1 = 1.9;
  Number a2 = 0.25; Number m2 = 3.0; Number n2 = 2.6; Number c2 = 4.2;
  Number g0 = cos(CV_MOTION_TWO_PI * (m0 * uv.x + n0 * uv.y) + c0);
  Number g1 = cos(CV_MOTION_TWO_PI * (m1 * uv.x + n1 * uv.y) + c1);
  Number g2 = cos(CV_MOTION_TWO_PI * (m2 * uv.x + n2 * uv.y) + c2);
  du = a0 * m0 * g0 + a1 * m1 * g1 + a2 * m2 * g2;
  dv = a0 * n0 * g0 + a1 * n1 * g1 + a2 * n2 * g2;
  Number nu = a0 * m0 + a1 * m1 + a2 * m2;
  Number nv = a0 * n0 + a1 * n1 + a2 * n2;
  return vec2(dv / nv, -du / nu);  // curl: (d psi/dv, -d psi/du)
}

// The seed's two phases half a period apart (its equations 1-2): P0 = frac(t * speed) and
// P1 = frac(t * speed + 0.5).
vec2 flow_phases(Number t, Number speed_hz) { return vec2(fract(t * speed_hz), fract(t * speed_hz + 0.5)); }

// The seed's blend of the two flow lookups s0 (at phase P0) and s1 (at P1), its equation 3: weight
// abs(0.5 - P0) * 2, so that each lookup's jump at its phase wrap has weight 0.
vec2 flow_blend(Number p0, vec2 s0, vec2 s1) { return mix(s0, s1, abs(0.5 - p0) * 2.0); }

// The seamless flow of the procedural map at (phase, height): continuous in t and h, in [-1, 1]^2,
// periodic in t with period 1 / speed_hz. A flow map given as an image (cloudgen/motion.h FlowMap)
// is looked up at the same two phases and blended by flow_blend.
vec2 flow_offset(Number t, Number h, Number speed_hz) {
  vec2 p = flow_phases(t, speed_hz);
  return flow_blend(p.x, procedural_flow(vec2(p.x, h)), procedural_flow(vec2(p.y, h)));
}

// Displacement in metres at height fraction ph (already clamped to [0, 1]) and time t, given the
// flow offset relative to its value at t = 0 (so that D(h, 0) = 0):
//  - wind along `wind_xz` at speed_mps, tops faster than bottoms: speed * (1 + shear * h);
//  - the seed's equation 5, pos' = pos + p_h * offset * (up, forward): the flow offset scaled by h
//    and by the up / forward amplitudes.
vec3 motion_displacement_of(Number t, Number ph, vec2 wind_xz, Number speed_mps, Number shear, vec2 off,
                            Number flow_up_m, Number flow_forward_m) {
  vec3 forward = vec3(wind_xz.x, 0.0, wind_xz.y);
  vec3 wind = forward * (speed_mps * t * (1.0 + shear * ph));
  return wind + vec3(0.0, ph * off.x * flow_up_m, 0.0) + forward * (ph * off.y * flow_forward_m);
}

// Displacement D(h, t) in metres of the cloud at height fraction h (clamped to [0, 1]) and time t
// with the procedural flow map.
vec3 motion_displacement(Number t, Number h, vec2 wind_xz, Number speed_mps, Number shear,
                         Number flow_hz, Number flow_up_m, Number flow_forward_m) {
  Number ph = clamp(h, 0.0, 1.0);
  vec2 off = flow_offset(t, ph, flow_hz) - flow_offset(0.0, ph, flow_hz);
  return motion_displacement_of(t, ph, wind_xz, speed_mps, shear, off, flow_up_m, flow_forward_m);
}
