// Temporal upsampling, step 2 (seed 003): the full-resolution cloud layer from this frame's fresh
// pixels (one per 4x4 block, cloud_sparse.frag) and last frame's result reprojected with the
// previous view-projection. A pixel marched this frame takes its fresh value. When the camera
// and the clouds stand still, every other pixel takes last frame's value as it is (so a still
// view converges to the full render in 16 frames): cloud_sparse_held.frag, which gl_renderer.cpp
// runs instead of cloud_sparse.frag, this pass and temporal_compose.frag then. Here (something
// moved) any other pixel reprojects its cloud point (at the cloud's opacity-weighted depth, moved
// back by the clouds' own motion since the last frame) into the previous frame, and takes the
// history there clamped into the range of the fresh pixels around it (neighbourhood clamping:
// moving clouds and parallax cannot leave ghosts), rejected (disocclusion) when its depth is
// outside the fresh neighbours' depths; falling back to the bilinear upsample of the fresh
// pixels when there is no history (the first frame, a resize, a changed setting) or the point
// was off screen last frame.
// Both stages run it: temporal_resolve.frag, and temporal_resolve.comp with render.compute.
// resolve_main() writes the outputs at the pixel centre g_frag (gl_FragCoord.xy, or the compute
// invocation's + 0.5).
vec2 g_frag;
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_fresh;          // quarter: (L, T)
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_fresh_depth;    // quarter: cloud distance
layout(binding = CV_UNIT_PASS_INPUT2) uniform sampler2D s_history;        // full, last frame: (L, T)
layout(binding = CV_UNIT_PASS_INPUT3) uniform sampler2D s_history_depth;  // full, last frame: distance

const float kFar = 5e5;  // reprojection distance of a pixel that sees no cloud (inside the 1e6 m far plane)
float depth_or_far(float d) { return d > 0.0 ? d : kFar; }

void resolve_main() {
  ivec2 px = ivec2(g_frag);
  ivec2 off = ivec2(u_temporal.zw);
  ivec2 qn = textureSize(s_fresh, 0);
  if ((px.x & 3) == off.x && (px.y & 3) == off.y) {  // marched this frame
    o_cloud = texelFetch(s_fresh, px >> 2, 0);
    o_depth = texelFetch(s_fresh_depth, px >> 2, 0);
    return;
  }
  // Fresh texel (i, j) sits at full-resolution pixel 4 (i, j) + off: bilinear between the four
  // around px (the spatial upsample), and their range (the closest the sparse samples allow).
  vec2 g = (vec2(px) - vec2(off)) / 4.0;
  ivec2 g0 = ivec2(floor(g));
  vec2 f = g - vec2(g0);
  vec4 spatial = vec4(0.0);
  float spatial_depth = 0.0;
  vec4 lo = vec4(1e30), hi = vec4(-1e30);
  float dlo = 1e30, dhi = 0.0, near_cloud = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 q = clamp(g0 + o, ivec2(0), qn - 1);
    float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    vec4 v = texelFetch(s_fresh, q, 0);
    float raw = texelFetch(s_fresh_depth, q, 0).r;
    float d = depth_or_far(raw);
    spatial += w * v;
    spatial_depth += w * d;
    lo = min(lo, v), hi = max(hi, v);
    dlo = min(dlo, d), dhi = max(dhi, d);
    if (raw > 0.0 && (near_cloud == 0.0 || raw < near_cloud)) near_cloud = raw;
  }
  vec4 fallback_depth = vec4(spatial_depth >= kFar * 0.5 ? 0.0 : spatial_depth, 0.0, 0.0, 0.0);
  if (u_temporal.x < 0.5) {
    o_cloud = spatial;
    o_depth = fallback_depth;
    return;
  }
  // The distance to reproject at: the cloud this pixel showed last frame (it moves on with the
  // wind, so its history follows it), else the nearest cloud among the fresh neighbours (a cloud
  // moving in), else none (sky and ground: the camera's motion only).
  float d = texelFetch(s_history_depth, px, 0).r;
  if (!(d > 0.0)) d = near_cloud;
  vec3 rd = pixel_ray(u_inv_view_proj, g_frag, u_viewport.xy);
  vec3 p = rd * depth_or_far(d);
  if (d > 0.0) p -= motion_at(p) - motion_at_previous(p);  // where it was last frame
  vec4 clip = u_prev_view_proj * vec4(p, 1.0);
  vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
  if (clip.w <= 0.0 || any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
    o_cloud = spatial;
    o_depth = fallback_depth;
    return;
  }
  vec4 history = texture(s_history, uv);
  float history_depth = depth_or_far(texture(s_history_depth, uv).r);
  if (history_depth < 0.5 * dlo || history_depth > 2.0 * dhi) {  // disoccluded: a different surface
    o_cloud = spatial;
    o_depth = fallback_depth;
    return;
  }
  o_cloud = clamp(history, lo, hi);
  o_depth = vec4(history_depth >= kFar * 0.5 ? 0.0 : history_depth, 0.0, 0.0, 0.0);
}
