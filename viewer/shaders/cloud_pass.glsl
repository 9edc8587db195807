// The full cloud pass's pixel (Olajos 2016, thesis 2.4: deferred shading and ray casting), for
// both of its stages: cloud.frag (a full-screen triangle, render.compute=false) and cloud.comp
// (one compute invocation per pixel). Each pixel's world ray comes from the inverse
// view-projection; compose_pixel (compose.glsl, shared with the CPU reference) marches up to the
// scene distance written by the ground pass and composites over it. px + 0.5 is gl_FragCoord.xy
// of the fragment stage, so both stages give the same bits.
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_scene_color;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_scene_distance;
vec4 cloud_pass_pixel(ivec2 px) {
  vec3 rd = pixel_ray(u_inv_view_proj, vec2(px) + 0.5, u_viewport.xy);
  float t_scene = texelFetch(s_scene_distance, px, 0).r;
  return vec4(compose_pixel(rd, px, t_scene, texelFetch(s_scene_color, px, 0).rgb), 1.0);
}
