// HDR resolve (thesis 2.7), the pixel of both stages (tonemap.frag, and .comp with
// render.compute): add the blurred bloom before tone mapping, expose, tone map (Reinhard L/(1+L)
// or ACES filmic), encode sRGB. The display image and the linear HDR frame.
layout(binding = CV_UNIT_PASS_INPUT0) uniform sampler2D s_hdr;
layout(binding = CV_UNIT_PASS_INPUT1) uniform sampler2D s_bloom;
void tonemap_pixel(ivec2 px, out vec4 display, out vec4 linear) {
  vec3 hdr = texelFetch(s_hdr, px, 0).rgb;
  if (u_post.z > 0.0) hdr += u_post.z * bilinear_fetch(s_bloom, (vec2(px) + 0.5) / u_viewport.xy);
  display = vec4(display_encode(hdr, u_post.x, int(u_post.y)), 1.0);
  linear = vec4(hdr, 1.0);
}
