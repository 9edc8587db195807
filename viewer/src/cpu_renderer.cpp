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

// The nanovdb path samples the grids through PNanoVDB.h's C mode, the code the GLSL mode is.
#define PNANOVDB_C
#include <nanovdb/PNanoVDB.h>

#include "cloudviewer/atmosphere.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/renderer.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/nvdb.h"
#endif

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

  CpuShader(const ref::CloudParams& p, const PreparedVolume& v, const std::vector<float>& m, const TransmittanceLut& t)
      : u_cloud(p), vol(v), mie(m), lut(t), u_atmo(t.params) {}

  vec3 transmittance_texel(ivec2 t) const { return lut.texels[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }

  vec4 volume_texel(ivec3 t) {
    if (vol.nano) return nanovdb_texel(t);
    const float* v = &vol.rgba[((size_t(t.z) * vol.dims[1] + t.y) * vol.dims[0] + t.x) * 4];
    return vec4(v[0], v[1], v[2], v[3]);
  }
  vec4 volume_filtered(vec3 uvw) { return vol.nano ? nanovdb_filtered(uvw) : volume_trilinear(uvw); }

  // The nanovdb path's lookups (shaders/volume_nanovdb.glsl, cloud_bindings.glsl on the GPU): a
  // PNanoVDB read accessor for the density and the first detail grid, kept across calls like the
  // GLSL globals (a CpuShader serves one thread); the other detail grids at the same offsets when
  // they share the first one's layout.
  mutable pnanovdb_readaccessor_t nvdb_acc[2];
  mutable bool nvdb_ready = false;
  pnanovdb_buf_t nvdb_buf() const {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    return pnanovdb_make_buf(reinterpret_cast<uint32_t*>(const_cast<uint8_t*>(vol.nano->data())), vol.nano->bytes() / 4);
#else
    return pnanovdb_make_buf(nullptr, 0);
#endif
  }
  uint64_t nvdb_grid(int g) const {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    const int index = g == 0 ? 0 : vol.nano->detail[size_t(g - 1)];
    return vol.nano->grids[size_t(std::max(index, 0))].offset;
#else
    return 0;
#endif
  }
  pnanovdb_root_handle_t nvdb_root(pnanovdb_buf_t buf, int g) const {
    pnanovdb_grid_handle_t h;
    h.address.byte_offset = nvdb_grid(g);
    return pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, h));
  }
  pnanovdb_address_t nvdb_address(int grid, ivec3 ijk) const {
    pnanovdb_buf_t buf = nvdb_buf();
    if (!nvdb_ready) {
      for (int g = 0; g < 2; ++g) pnanovdb_readaccessor_init(&nvdb_acc[g], nvdb_root(buf, g));
      nvdb_ready = true;
    }
    pnanovdb_coord_t c{ijk.x, ijk.y, ijk.z};
    return pnanovdb_readaccessor_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, buf, &nvdb_acc[grid], &c);
  }
  Number nanovdb_density(ivec3 ijk) const { return pnanovdb_read_float(nvdb_buf(), nvdb_address(0, ijk)); }
  vec3 nanovdb_detail(ivec3 ijk) const {
    pnanovdb_buf_t buf = nvdb_buf();
    pnanovdb_address_t a = nvdb_address(1, ijk);
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    if (vol.nano->detail_shared_layout) {
      pnanovdb_address_t b = a, c = a;
      b.byte_offset += nvdb_grid(2) - nvdb_grid(1);
      c.byte_offset += nvdb_grid(3) - nvdb_grid(1);
      return vec3(pnanovdb_read_float(buf, a), pnanovdb_read_float(buf, b), pnanovdb_read_float(buf, c));
    }
#endif
    vec3 r(pnanovdb_read_float(buf, a), 0.0, 0.0);
    pnanovdb_coord_t c{ijk.x, ijk.y, ijk.z};
    for (int g = 2; g < 4; ++g)
      r[g - 1] = pnanovdb_read_float(buf, pnanovdb_root_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, buf, nvdb_root(buf, g), &c));
    return r;
  }
  ivec3 nanovdb_index_min() const {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    return ivec3(vol.nano->index_min[0], vol.nano->index_min[1], vol.nano->index_min[2]);
#else
    return ivec3(0);
#endif
  }
  bool nanovdb_has_detail() const { return vol.has_detail; }
  Number occupancy_texel(ivec3 c) const {
    return vol.occ[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
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
#include "../shaders/volume_nanovdb.glsl"
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
  tbb::parallel_for(0, h, [&](int y) {
    CpuShader sh(P, vol, mie, lut);
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
