// CPU reference renderer: the shared GLSL math (shaders/cloud_functions.glsl) compiled as C++ in
// double precision inside a class (Bruneton's reference/functions.cc pattern), TBB over pixels.
// Where the GPU may legitimately differ: float vs double arithmetic everywhere, the texture unit's
// trilinear weights (llvmpipe and GPUs quantise them; `render.exact_filter=true` filters by hand on
// the GPU too) and pixels at the ground quad's far edge. Everything else is the same formula.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_for.h>

#include "cloudviewer/renderer.h"

namespace cloudviewer {
namespace {

using namespace glm;

struct CpuShader {
  using Number = double;
  using vec2 = glm::dvec2;
  using vec3 = glm::dvec3;
  using vec4 = glm::dvec4;
  using ivec2 = glm::ivec2;
  using ivec3 = glm::ivec3;
  using uint = uint32_t;

  const ref::CloudParams& u_cloud;
  const PreparedVolume& vol;
  const std::vector<float>& mie;

  CpuShader(const ref::CloudParams& p, const PreparedVolume& v, const std::vector<float>& m)
      : u_cloud(p), vol(v), mie(m) {}

  vec4 volume_texel(ivec3 t) const {
    const float* v = &vol.rgba[((size_t(t.z) * vol.dims[1] + t.y) * vol.dims[0] + t.x) * 4];
    return vec4(v[0], v[1], v[2], v[3]);
  }
  vec4 volume_filtered(vec3 uvw) { return volume_trilinear(uvw); }
  Number occupancy_texel(ivec3 c) const {
    return vol.occ[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
  Number mie_table_value(int i) const { return mie[size_t(i)]; }
  vec2 coverage_texel(ivec2 t) const {
    const float* c = &coverage_map()[(size_t(t.y) * 256 + size_t(t.x)) * 2];
    return vec2(c[0], c[1]);
  }
  ivec2 coverage_size() const { return ivec2(256, 256); }

#define IN(x) const x&
#define OUT(x) x&
#define INOUT(x) x&
#include "../shaders/cloud_functions.glsl"
#undef IN
#undef OUT
#undef INOUT
};

struct Buffer {
  int w, h;
  std::vector<dvec3> px;
  Buffer(int w_, int h_) : w(w_), h(h_), px(size_t(w_) * h_, dvec3(0.0)) {}
  dvec3& at(int x, int y) { return px[size_t(y) * w + x]; }
  const dvec3& at(int x, int y) const { return px[size_t(y) * w + x]; }
};

// Same arithmetic as bilinear_fetch in shaders/post_common.glsl.
dvec3 bilinear(const Buffer& b, dvec2 uv) {
  dvec2 x = uv * dvec2(b.w, b.h) - 0.5;
  dvec2 fl = floor(x);
  dvec2 f = x - fl;
  ivec2 i0 = ivec2(fl);
  dvec3 acc(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 o(k & 1, k >> 1);
    ivec2 i = clamp(i0 + o, ivec2(0), ivec2(b.w - 1, b.h - 1));
    dvec2 wt = mix(dvec2(1.0) - f, f, dvec2(o));
    acc += (wt.x * wt.y) * b.at(i.x, i.y);
  }
  return acc;
}

}  // namespace

double reference_phase(PhaseMode mode, double g, double cos_theta) {
  ref::CloudParams p{};
  p.phase = dvec4(double(int(mode)), g, double(mie_phase_table().size()), 0.0);
  PreparedVolume empty;
  CpuShader sh(p, empty, mie_phase_table());
  return sh.phase_function(cos_theta);
}

FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame) {
  const int w = frame.width, h = frame.height;
  const std::vector<float>& mie = mie_phase_table();
  const ref::CloudParams& P = frame.params;
  Buffer hdr(w, h);
  std::vector<double> transmittance(size_t(w) * h, 1.0);
  const int output = int(P.control.w);
  tbb::parallel_for(0, h, [&](int y) {
    CpuShader sh(P, vol, mie);
    for (int x = 0; x < w; ++x) {
      dvec2 ndc((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0);
      dvec4 near_point = frame.inv_view_proj * dvec4(ndc, -1.0, 1.0);
      dvec3 rd = normalize(dvec3(near_point) / near_point.w);
      double t_scene = 1e30;
      dvec3 background(0.0);
      // The GL ground quad is visible from both sides; so is this plane. In layer mode the ground
      // is the parabolic Earth (altitude 0), tessellated finely on the GPU.
      double t = -1;
      if (P.ground.z > 0.5 && P.layer.x > 0.5) {
        dvec2 r = sh.parabola_roots((1.0 - rd.y * rd.y) / (2.0 * P.layer.w), rd.y, -P.ground.x);
        if (r.x <= r.y) t = r.x > 0 ? r.x : r.y;
      } else if (P.ground.z > 0.5 && rd.y != 0.0 && P.ground.x / rd.y > 0.0) {
        t = P.ground.x / rd.y;
      }
      if (t > 0) {
        dvec3 p = rd * t;
        if (std::abs(p.x) <= P.ground.w && std::abs(p.z) <= P.ground.w) {
          t_scene = t;
          background = sh.ground_radiance(p);
        }
      }
      if (t_scene >= 1e29) background = sh.sky_radiance(rd);
      double jitter = P.control.x > 0.5 ? sh.jitter_offset(ivec2(x, y), int(P.control.y)) : 0.5;
      int iterations = 0;
      double t_mean = 0;
      dvec4 m = sh.march_clouds(rd, t_scene, jitter, iterations, t_mean);
      m = sh.aerial_perspective(m, t_mean, rd);
      dvec3 c;
      if (output == 1) c = dvec3(m.w);
      else if (output == 2) c = dvec3(iterations, m.w, 0.0);
      else c = dvec3(m) + m.w * background;
      hdr.at(x, y) = c;
    }
  });

  // Bloom: half-resolution bright pass, separable Gaussian, added before tone mapping
  // (the same passes and arithmetic as bloom_bright.frag, bloom_blur.frag, tonemap.frag).
  const double exposure = frame.settings.exposure, strength = frame.settings.bloom;
  const double threshold = frame.settings.bloom_threshold;
  const int op = int(frame.settings.tonemap);
  const int bw = std::max(1, w / 2), bh = std::max(1, h / 2);
  Buffer bright(bw, bh), blur_h(bw, bh), blur_v(bw, bh);
  CpuShader sh(P, vol, mie);
  if (strength > 0) {
    const int radius = 6;
    const double sigma = 3.0;
    std::vector<double> wts;
    for (int i = -radius; i <= radius; ++i) wts.push_back(sh.gaussian_weight(i, radius, sigma));
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x)
        bright.at(x, y) = sh.bloom_bright(bilinear(hdr, dvec2((x + 0.5) / bw, (y + 0.5) / bh)), threshold);
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x) {
        dvec3 acc(0.0);
        for (int i = -radius; i <= radius; ++i) acc += wts[size_t(i + radius)] * bright.at(std::clamp(x + i, 0, bw - 1), y);
        blur_h.at(x, y) = acc;
      }
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x) {
        dvec3 acc(0.0);
        for (int i = -radius; i <= radius; ++i) acc += wts[size_t(i + radius)] * blur_h.at(x, std::clamp(y + i, 0, bh - 1));
        blur_v.at(x, y) = acc;
      }
  }
  FrameImages out{Image(w, h), Image(w, h)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      dvec3 c = hdr.at(x, y);
      if (strength > 0) c += strength * bilinear(blur_v, dvec2((x + 0.5) / w, (y + 0.5) / h));
      dvec3 d = sh.srgb_encode(sh.tone_map(c, exposure, op));
      float* pd = out.display.at(x, y);
      float* pl = out.linear.at(x, y);
      for (int k = 0; k < 3; ++k) {
        pd[k] = float(d[k]);
        pl[k] = float(c[k]);
      }
      pd[3] = pl[3] = 1.f;
    }
  return out;
}

}  // namespace cloudviewer
