// CPU reference renderer: the shared GLSL headers (shaders/*.glsl, listed in march.glsl) compiled
// as C++ in double precision inside a class (Bruneton's reference/functions.cc pattern), TBB over
// pixels. Where the GPU may legitimately differ: float vs double arithmetic everywhere, the texture
// unit's trilinear weights (llvmpipe and GPUs quantise them; `render.exact_filter=true` filters by
// hand on the GPU too) and pixels at the ground quad's far edge. Everything else is the same
// formula: the per-pixel compose, the bloom taps, the bilinear taps and the tone map included.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_for.h>

#include "cloudviewer/atmosphere.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/renderer.h"

namespace cloudviewer {
namespace {

using namespace glm;

struct CpuShader {
  using Number = double;
  using vec2 = glm::dvec2;
  using vec3 = glm::dvec3;
  using vec4 = glm::dvec4;
  using mat4 = glm::dmat4;
  using ivec2 = glm::ivec2;
  using ivec3 = glm::ivec3;
  using uint = uint32_t;

  const ref::CloudParams& u_cloud;
  const PreparedVolume& vol;
  const std::vector<float>& mie;
  const TransmittanceLut& lut;
  const ref::AtmosphereParams& u_atmo;
  const std::vector<double>* light_volume = nullptr;  ///< light_volume_dims texels, x fastest

  CpuShader(const ref::CloudParams& p, const PreparedVolume& v, const std::vector<float>& m, const TransmittanceLut& t)
      : u_cloud(p), vol(v), mie(m), lut(t), u_atmo(t.params) {}

  vec3 transmittance_texel(ivec2 t) const { return lut.texels[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }

  vec4 volume_texel(ivec3 t) const {
    const float* v = &vol.rgba[((size_t(t.z) * vol.dims[1] + t.y) * vol.dims[0] + t.x) * 4];
    return vec4(v[0], v[1], v[2], v[3]);
  }
  vec4 volume_filtered(vec3 uvw) { return volume_trilinear(uvw); }
  Number occupancy_texel(ivec3 c) const {
    return vol.occ[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
  int distance_texel(ivec3 c) const {
    return vol.dist[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
  Number light_volume_texel(ivec3 t) const {
    const ivec3 n = ivec3(u_cloud.light_volume_dims);
    return (*light_volume)[(size_t(t.z) * n.y + t.y) * n.x + t.x];
  }
  Number light_volume_filtered(vec3 uvw) { return light_volume_trilinear(uvw); }
  Number mie_table_value(int i) const { return mie[size_t(i)]; }
  vec2 coverage_texel(ivec2 t) const {
    const float* c = &coverage_map()[(size_t(t.y) * CV_COVERAGE_MAP_SIZE + size_t(t.x)) * 2];
    return vec2(c[0], c[1]);
  }
  ivec2 coverage_size() const { return ivec2(CV_COVERAGE_MAP_SIZE, CV_COVERAGE_MAP_SIZE); }

#define IN(x) const x&
#define OUT(x) x&
#define INOUT(x) x&
// The list and order of shaders/cloud_headers.glsl (after its GLSL-only bindings), plus post.glsl.
#include "../shaders/common.glsl"
#include "../shaders/phase.glsl"
#include "cloudgen/cloud_type.glsl"
#include "../shaders/medium.glsl"
#include "../shaders/atmosphere.glsl"
#include "../shaders/sky_atmosphere.glsl"
#include "../shaders/lighting.glsl"
#include "../shaders/march.glsl"
#include "../shaders/sky.glsl"
#include "../shaders/compose.glsl"
#include "../shaders/post.glsl"
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
  ivec2 size() const { return ivec2(w, h); }
};

// post.glsl's bilinear taps over a buffer (post_sampling.glsl's bilinear_fetch on the GPU).
dvec3 bilinear(CpuShader& sh, const Buffer& b, dvec2 uv) {
  dvec3 acc(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 texel;
    double w = sh.bilinear_tap(uv, b.size(), k, texel);
    acc += w * b.at(texel.x, texel.y);
  }
  return acc;
}

// One direction of the separable bloom blur (bloom_blur.frag).
void blur(CpuShader& sh, const Buffer& src, Buffer& dst, ivec2 direction) {
  for (int y = 0; y < src.h; ++y)
    for (int x = 0; x < src.w; ++x) {
      dvec3 acc(0.0);
      for (int i = -CV_BLOOM_RADIUS; i <= CV_BLOOM_RADIUS; ++i) {
        ivec2 q;
        double w = sh.bloom_tap(ivec2(x, y), direction, i, src.size(), q);
        acc += w * src.at(q.x, q.y);
      }
      dst.at(x, y) = acc;
    }
}

// A LUT for CpuShaders that never read it (the analytic sky, the phase and gradient helpers).
const TransmittanceLut& no_lut() {
  static const TransmittanceLut empty{};
  return empty;
}

}  // namespace

std::vector<double> build_light_volume_cpu(const PreparedVolume& vol, const ref::CloudParams& params) {
  const glm::ivec3 n = glm::ivec3(params.light_volume_dims);
  std::vector<double> tau(size_t(n.x) * n.y * n.z, 0.0);
  tbb::parallel_for(0, n.z, [&](int z) {
    CpuShader sh(params, vol, mie_phase_table(), no_lut());
    for (int y = 0; y < n.y; ++y)
      for (int x = 0; x < n.x; ++x)
        tau[(size_t(z) * n.y + y) * n.x + x] = sh.light_optical_depth(sh.light_volume_position(ivec3(x, y, z)));
  });
  return tau;
}

double reference_light_optical_depth(const PreparedVolume& vol, const ref::CloudParams& params, glm::dvec3 p,
                                     const std::vector<double>* light_volume) {
  CpuShader sh(params, vol, mie_phase_table(), no_lut());
  sh.light_volume = light_volume;
  return light_volume ? sh.light_volume_tau(p) : sh.light_optical_depth(p);
}

double reference_phase(PhaseMode mode, double g, double cos_theta) {
  ref::CloudParams p{};
  p.phase_mode = double(int(mode));
  p.hg_g = g;
  p.mie_table_size = double(mie_phase_table().size());
  PreparedVolume empty;
  CpuShader sh(p, empty, mie_phase_table(), no_lut());
  return sh.phase_function(cos_theta);
}

double reference_cloud_type_gradient(double h, double type) {
  ref::CloudParams p{};
  PreparedVolume empty;
  CpuShader sh(p, empty, mie_phase_table(), no_lut());
  return sh.cloud_type_gradient(h, type);
}

FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame) {
  const int w = frame.width, h = frame.height;
  const std::vector<float>& mie = mie_phase_table();
  const ref::CloudParams& P = frame.params;
  std::shared_ptr<const TransmittanceLut> shared =
      int(P.sky_mode) == CV_SKY_PRECOMPUTED ? shared_transmittance_lut(frame.settings.atmosphere) : nullptr;
  const TransmittanceLut& lut = shared ? *shared : no_lut();
  Buffer hdr(w, h);
  // The light volume, when on: the same texels the light_volume pass computes, in double precision.
  std::vector<double> light_volume;
  if (P.light_volume_on > 0.5) light_volume = build_light_volume_cpu(vol, P);
  tbb::parallel_for(0, h, [&](int y) {
    CpuShader sh(P, vol, mie, lut);
    sh.light_volume = &light_volume;
    for (int x = 0; x < w; ++x) {
      dvec3 rd = sh.pixel_ray(frame.inv_view_proj, dvec2(x + 0.5, y + 0.5), dvec2(w, h));
      double t_scene = CV_NO_HIT;
      dvec3 scene_color(0.0);
      // The GPU rasterises the ground mesh (ground.vert); here the same surface is intersected. The
      // GL ground quad is visible from both sides; so is this plane. In layer mode the ground is the
      // parabolic Earth (altitude 0), tessellated finely on the GPU.
      double t = -1;
      if (P.ground_on > 0.5 && P.layer_on > 0.5) {
        dvec2 r = sh.parabola_roots((1.0 - rd.y * rd.y) / (2.0 * P.earth_radius_m), rd.y, -P.ground_y_m);
        if (r.x <= r.y) t = r.x > 0 ? r.x : r.y;
      } else if (P.ground_on > 0.5 && rd.y != 0.0 && P.ground_y_m / rd.y > 0.0) {
        t = P.ground_y_m / rd.y;
      }
      if (t > 0) {
        dvec3 p = rd * t;
        if (std::abs(p.x) <= P.ground_half_extent_m && std::abs(p.z) <= P.ground_half_extent_m) {
          t_scene = t;
          scene_color = sh.ground_radiance(p);
        }
      }
      hdr.at(x, y) = sh.compose_pixel(rd, ivec2(x, y), t_scene, scene_color);
    }
  });

  // Bloom: half-resolution bright pass, separable Gaussian, added before tone mapping
  // (the same passes and taps as bloom_bright.frag, bloom_blur.frag, tonemap.frag).
  const double exposure = frame.settings.exposure, strength = frame.settings.bloom;
  const double threshold = frame.settings.bloom_threshold;
  const int op = int(frame.settings.tonemap);
  const int bw = std::max(1, w / 2), bh = std::max(1, h / 2);
  Buffer bright(bw, bh), blur_h(bw, bh), blur_v(bw, bh);
  CpuShader sh(P, vol, mie, lut);
  if (strength > 0) {
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x)
        bright.at(x, y) = sh.bloom_bright(bilinear(sh, hdr, dvec2((x + 0.5) / bw, (y + 0.5) / bh)), threshold);
    blur(sh, bright, blur_h, ivec2(1, 0));
    blur(sh, blur_h, blur_v, ivec2(0, 1));
  }
  FrameImages out{Image(w, h), Image(w, h)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      dvec3 c = hdr.at(x, y);
      if (strength > 0) c += strength * bilinear(sh, blur_v, dvec2((x + 0.5) / w, (y + 0.5) / h));
      dvec3 d = sh.display_encode(c, exposure, op);
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
