// CPU reference renderer: the shared GLSL headers (shaders/*.glsl, listed in march.glsl) compiled
// as C++ in double precision inside a class (Bruneton's reference/functions.cc pattern), TBB over
// pixels. Where the GPU may legitimately differ: float vs double arithmetic everywhere, the texture
// unit's trilinear weights (llvmpipe and GPUs quantise them; `render.exact_filter=true` filters by
// hand on the GPU too) and pixels at the ground quad's far edge. Everything else is the same
// formula: the per-pixel compose, the bloom taps, the bilinear taps and the tone map included.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <tbb/parallel_for.h>

// The nanovdb path samples the grids through PNanoVDB.h's C mode, the code the GLSL mode is.
#define PNANOVDB_C
#include <nanovdb/PNanoVDB.h>

#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/detail_texture.h"
#include "cloudviewer/renderer.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/nvdb.h"
#endif
#include "cloudgen/motion.h"
#include "cloudgen/phase.h"
#include "cpu/glsl_cpp.h"  // last: defines IN/OUT/INOUT

namespace cloudviewer {
namespace {

using namespace glm;

// The camera's air LUT (render.air_lut) of one frame: each texel computed by atmosphere.glsl's
// compute_air_texel the first time a pixel reads it, shared by the threads.
struct AirTexels {
  std::mutex mutex;
  std::unordered_map<int64_t, std::array<dvec3, 2>> texels;
};

struct CpuShader {
  CV_GLSL_DOUBLE_TYPES;

  const ref::CloudParams& u_cloud;
  const PreparedVolume& vol;
  /// The frame's Mie table; without one, the computed table, fetched at the first Mie lookup
  /// (computing it takes seconds).
  mutable std::shared_ptr<const MiePhaseTable> mie;
  /// The frame's coverage map (layer mode); without one, the procedural map.
  mutable std::shared_ptr<const std::vector<float>> coverage;
  const AtmosphereLuts& lut;
  const ref::AtmosphereParams& u_atmo;
  const std::vector<dvec3>* motion = nullptr;  // FrameSetup::motion_table (2 rows)
  const std::vector<uint8_t>* moved_occ = nullptr;  // FrameSetup::moved_occupancy (moving clouds, box mode)
  const std::vector<double>* light_volume = nullptr;  ///< light_volume_dims texels, x fastest

  CpuShader(const ref::CloudParams& p, const PreparedVolume& v, const AtmosphereLuts& t,
            const FrameSetup* frame = nullptr)
      : u_cloud(p), vol(v), mie(frame ? frame->mie : nullptr), coverage(frame ? frame->coverage : nullptr), lut(t), u_atmo(t.params),
        motion(frame ? &frame->motion_table : nullptr), moved_occ(frame ? &frame->moved_occupancy : nullptr) {}

  vec3 transmittance_texel(ivec2 t) const { return lut.transmittance[size_t(t.y) * CV_TRANSMITTANCE_W + size_t(t.x)]; }
  vec3 transmittance_filtered(vec2 uv) { return transmittance_bilinear(uv); }  // exact, as the texture unit
  vec3 multiple_scattering_texel(ivec2 t) const {
    return lut.multiple_scattering[size_t(t.y) * CV_MS_LUT_SIZE + size_t(t.x)];
  }
  vec3 irradiance_texel(int t) const { return lut.irradiance[size_t(t)]; }
  // The 4D scattering LUT (render.sky_lut): each texel computed by atmosphere.glsl's
  // compute_scattering_texel the first time a pixel reads it, shared by the threads and the frames.
  const std::array<dvec3, 3>& lut_texel(ivec3 t) {
    const int64_t key = (int64_t(t.z) * CV_SCATTERING_MU + t.y) * (CV_SCATTERING_NU * CV_SCATTERING_MU_S) + t.x;
    ScatteringTexels& table = *lut.scattering;
    {
      std::lock_guard<std::mutex> lock(table.mutex);
      auto it = table.texels.find(key);
      if (it != table.texels.end()) return it->second;
    }
    std::array<dvec3, 3> v;
    compute_scattering_texel(t, v[0], v[1], v[2]);
    std::lock_guard<std::mutex> lock(table.mutex);
    return table.texels.emplace(key, v).first->second;  // unordered_map: references stay valid
  }
  vec3 scattering_texel(ivec3 t) { return lut_texel(t)[0]; }
  vec3 single_mie_texel(ivec3 t) { return lut_texel(t)[1]; }
  vec3 scattering_multiple_texel(ivec3 t) { return lut_texel(t)[2]; }
  AirTexels* air = nullptr;  ///< this frame's air LUT; null: each read computes its texel again
  vec3 air_texel(int part, ivec3 t) {
    std::array<dvec3, 2> v;
    if (!air) {
      frame_air_texel(t, v[0], v[1]);
      return v[size_t(part)];
    }
    const int64_t key = (int64_t(t.z) * CV_AIR_ELEVATION + t.y) * CV_AIR_AZIMUTH + t.x;
    {
      std::lock_guard<std::mutex> lock(air->mutex);
      auto it = air->texels.find(key);
      if (it != air->texels.end()) return it->second[size_t(part)];
    }
    frame_air_texel(t, v[0], v[1]);
    std::lock_guard<std::mutex> lock(air->mutex);
    return air->texels.emplace(key, v).first->second[size_t(part)];
  }
  vec3 orders_texel(int part, ivec3 t) const { return part == 4 ? lut.orders_sum()[orders_index(t)] : vec3(0.0); }
  vec3 orders_irradiance_texel(int) const { return vec3(0.0); }

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
  // render.skipping=tree (volume_nanovdb.glsl nanovdb_empty_box): the edge of the density grid's
  // node holding ijk when it is a tile of value <= 0 (read as 0) or the background, else 0; one
  // walk from the root, as on the GPU.
  int nanovdb_density_empty_dim(ivec3 ijk) const {
    if (!vol.nano) return 0;
    pnanovdb_buf_t buf = nvdb_buf();
    pnanovdb_coord_t c{ijk.x, ijk.y, ijk.z};
    pnanovdb_uint32_t level = 0;
    const pnanovdb_address_t a =
        pnanovdb_root_get_value_address_and_level(PNANOVDB_GRID_TYPE_FLOAT, buf, nvdb_root(buf, 0), &c, &level);
    if (level == 0 || pnanovdb_read_float(buf, a) > 0.0f) return 0;
    return level == 1 ? 8 : level == 2 ? 128 : 4096;  // a lower, upper or root node's tile (or the background)
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
  // A moving frame's grid over the march box (box mode; medium.glsl moved_grid): cell c of
  // `grid`, or `none` when the frame did not give it.
  bool reads_moved_grid() const { return u_cloud.motion_on > 0.5 && u_cloud.layer_on < 0.5; }
  int moved_texel(const std::vector<uint8_t>* grid, ivec3 c, int none) const {
    const ivec3 n = ivec3(u_cloud.moved_occ_dims);
    if (!grid || grid->size() != size_t(n.x) * n.y * n.z) return none;
    return (*grid)[(size_t(c.z) * n.y + c.y) * n.x + c.x];
  }
  Number occupancy_texel(ivec3 c) const {
    if (reads_moved_grid()) return moved_texel(moved_occ, c, 1);  // none given: may hold density
    return vol.occ[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
  int distance_texel(ivec3 c) const {
    return vol.dist[(size_t(c.z) * vol.occ_dims[1] + c.y) * vol.occ_dims[0] + c.x];
  }
  Number light_volume_texel(ivec3 t) const {
    const ivec3 n = ivec3(u_cloud.light_volume_dims);
    return (*light_volume)[(size_t(t.z) * n.y + t.y) * n.x + t.x];
  }
  Number light_volume_filtered(vec3 uvw) { return grid_trilinear(false, uvw).x; }
  const std::vector<double>* shadow_map = nullptr;  ///< shadow_map_nx x shadow_map_nz texels, x fastest
  Number shadow_map_texel(ivec2 t) const { return (*shadow_map)[size_t(t.y) * size_t(u_cloud.shadow_map_nx) + size_t(t.x)]; }
  const std::vector<dvec4>* ms_volume = nullptr;  ///< ms_volume_dims cells (ms_volume_texels), x fastest
  vec4 ms_volume_texel(ivec3 t) const {
    const ivec3 n = ivec3(u_cloud.ms_volume_dims);
    return (*ms_volume)[(size_t(t.z) * n.y + t.y) * n.x + t.x];
  }
  vec4 ms_volume_filtered(vec3 uvw) { return grid_trilinear(true, uvw); }
  vec3 mie_table_value(int i) const {
    if (!mie) mie = computed_mie_table();
    return vec3(mie->at(i, 0), mie->at(i, 1), mie->at(i, 2));
  }
  vec2 coverage_texel(ivec2 t) const {
    if (!coverage) coverage = procedural_coverage_map();
    const float* c = &(*coverage)[(size_t(t.y) * CV_COVERAGE_MAP_SIZE + size_t(t.x)) * 2];
    return vec2(c[0], c[1]);
  }
  ivec2 coverage_size() const { return ivec2(CV_COVERAGE_MAP_SIZE, CV_COVERAGE_MAP_SIZE); }
  vec3 motion_texel(int i, int row) const { return (*motion)[size_t(row) * CV_MOTION_LUT_SIZE + size_t(i)]; }
  vec3 curl_texel(ivec3 i) const { return cloudgen::curl_field_texel(i.x, i.y, i.z); }
  // render.detail's texture (detail_texture.h), fetched at the first lookup.
  mutable std::shared_ptr<const std::vector<float>> fine_detail;
  Number fine_detail_texel(ivec3 t) const {
    const size_t n = size_t(u_cloud.fine_detail_size);
    if (!fine_detail) fine_detail = detail_texture(int(n));
    return (*fine_detail)[(size_t(t.z) * n + size_t(t.y)) * n + size_t(t.x)];
  }
  Number fine_detail_filtered(vec3 q) { return fine_detail_trilinear(q); }  // exact, as the texture unit

// The modes, the cloud maths in their one order (shaders/cloud_math.glsl), and the post passes.
#include "../../shaders/modes.glsl"
#include "../../shaders/cloud_math.glsl"
#include "../../shaders/post.glsl"
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

// One direction of the separable bloom blur (bloom_blur.glsl).
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
const AtmosphereLuts& no_lut() {
  static const AtmosphereLuts empty{};
  return empty;
}

}  // namespace

std::vector<double> build_shadow_map_cpu(const PreparedVolume& vol, const FrameSetup& frame) {
  const ref::CloudParams& P = frame.params;
  const int nx = int(P.shadow_map_nx), nz = int(P.shadow_map_nz);
  std::vector<double> t(size_t(std::max(nx, 0)) * size_t(std::max(nz, 0)), 1.0);
  tbb::parallel_for(0, std::max(nz, 0), [&](int z) {
    CpuShader sh(P, vol, no_lut(), &frame);
    for (int x = 0; x < nx; ++x) t[size_t(z) * size_t(nx) + size_t(x)] = sh.sun_shadow_transmittance(sh.shadow_map_position(ivec2(x, z)));
  });
  return t;
}

std::vector<double> build_light_volume_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                           const FrameSetup* frame) {
  const glm::ivec3 n = glm::ivec3(params.light_volume_dims);
  std::vector<double> tau(size_t(n.x) * n.y * n.z, 0.0);
  if (params.motion_on > 0.5 && (!frame || frame->motion_table.empty()))
    throw std::invalid_argument("build_light_volume_cpu: moving clouds need the frame's motion table");
  tbb::parallel_for(0, n.z, [&](int z) {
    CpuShader sh(params, vol, no_lut(), frame);
    for (int y = 0; y < n.y; ++y)
      for (int x = 0; x < n.x; ++x)
        tau[(size_t(z) * n.y + y) * n.x + x] = sh.light_volume_value(ivec3(x, y, z));
  });
  return tau;
}

MsDiffusionGrid ms_diffusion_grid(const ref::CloudParams& params) {
  MsDiffusionGrid g;
  g.dims = glm::ivec3(params.ms_volume_dims);
  g.cell_m = params.volume_size_m / glm::dvec3(g.dims);
  g.tiles_xz = false;  // one box of cloud: vacuum beyond every face (lighting.glsl ms_volume_source)
  const size_t cells = size_t(g.dims.x) * g.dims.y * g.dims.z;
  g.sigma_t.assign(cells, 0.0);
  g.source.assign(cells, 0.0);
  return g;
}

MsDiffusionGrid build_ms_source_cpu(const PreparedVolume& vol, const ref::CloudParams& params,
                                    const std::vector<double>* light_volume) {
  MsDiffusionGrid g = ms_diffusion_grid(params);
  tbb::parallel_for(0, g.dims.z, [&](int z) {
    CpuShader sh(params, vol, no_lut());
    sh.light_volume = light_volume;
    for (int y = 0; y < g.dims.y; ++y)
      for (int x = 0; x < g.dims.x; ++x) {
        const dvec2 s = sh.ms_volume_source(ivec3(x, y, z));
        const size_t i = (size_t(z) * g.dims.y + y) * g.dims.x + x;
        g.sigma_t[i] = s.x;
        g.source[i] = s.y;
      }
  });
  return g;
}

double phase_asymmetry(const ref::CloudParams& params, const std::shared_ptr<const MiePhaseTable>& mie) {
  // cloudgen's table angles: fine steps near the forward peak (the Mie table's is ~10^6 times its side value).
  const std::vector<double> angle = cloudgen::phase::table_angles();
  std::vector<double> value;
  PreparedVolume empty;
  CpuShader sh(params, empty, no_lut());
  sh.mie = mie;
  for (double a : angle) value.push_back(sh.phase_function_rgb(std::cos(glm::radians(a))).y);
  return cloudgen::phase::asymmetry(angle, value);
}

MsDiffusionOptions ms_diffusion_options(const ref::CloudParams& params,
                                        const std::shared_ptr<const MiePhaseTable>& mie) {
  MsDiffusionOptions o;
  o.albedo = params.albedo;
  o.asymmetry = std::clamp(phase_asymmetry(params, mie), -0.99, 0.99);
  return o;
}

double reference_light_optical_depth(const PreparedVolume& vol, const ref::CloudParams& params, glm::dvec3 p,
                                     const std::vector<double>* light_volume) {
  CpuShader sh(params, vol, no_lut());
  sh.light_volume = light_volume;
  return light_volume ? sh.light_volume_tau(p) : sh.light_optical_depth(p);
}

double reference_ground_shadow(const PreparedVolume& vol, const FrameSetup& frame, glm::dvec3 p,
                               const std::vector<double>* shadow_map) {
  CpuShader sh(frame.params, vol, no_lut(), &frame);
  sh.shadow_map = shadow_map;
  return shadow_map ? sh.shadow_map_lookup(p) : sh.sun_shadow_transmittance(p);
}

glm::dvec3 reference_phase_rgb(const RenderSettings& s, double cos_theta) {
  ref::CloudParams p{};
  set_phase_params(p, s);
  p.mie_table_size = CV_MIE_TABLE_SIZE;
  PreparedVolume empty;
  CpuShader sh(p, empty, no_lut());
  if (s.phase == PhaseMode::Mie) sh.mie = mie_table_of(s);
  return sh.phase_function_rgb(cos_theta);
}

// phase_function is phase_function_rgb's green channel (the Mie table's) or its grey lobe.
double reference_phase(const RenderSettings& s, double cos_theta) { return reference_phase_rgb(s, cos_theta).y; }

double reference_phase(PhaseMode mode, double g, double cos_theta) {
  RenderSettings s;
  s.phase = mode;
  s.g = g;
  return reference_phase(s, cos_theta);
}

double reference_cloud_type_gradient(double h, double type) {
  ref::CloudParams p{};
  PreparedVolume empty;
  CpuShader sh(p, empty, no_lut());
  return sh.cloud_type_gradient(h, type);
}

glm::ivec2 reference_cross_matrix_offset(int frame) {
  ref::CloudParams p{};
  PreparedVolume empty;
  CpuShader sh(p, empty, no_lut());
  return sh.cross_matrix_offset(frame);
}

int reference_cross_matrix(int x, int y) {
  ref::CloudParams p{};
  PreparedVolume empty;
  CpuShader sh(p, empty, no_lut());
  return sh.cross_matrix(x, y);
}

void reference_air_carried(const glm::dvec3& inscattered, const glm::dvec3& transmittance, double t_k, double t,
                           glm::dvec3& inscattered_t, glm::dvec3& transmittance_t) {
  ref::CloudParams p{};
  PreparedVolume empty;
  CpuShader sh(p, empty, no_lut());
  glm::dvec3 s(0.0), e(0.0);
  sh.air_coefficients(inscattered, transmittance, t_k, s, e);
  sh.air_over_distance(s, e, t, inscattered_t, transmittance_t);
}

double reference_density(const PreparedVolume& vol, const FrameSetup& frame, const glm::dvec3& p) {
  CpuShader sh(frame.params, vol, no_lut(), &frame);
  return sh.cloud_density(p);
}

namespace {

// What the camera ray rd hits first: the ground (its radiance, shadows included, and distance) or
// nothing (t_scene = CV_NO_HIT). The GPU rasterises the ground mesh (ground.vert); here the same
// surface is intersected. The GL ground quad is visible from both sides; so is this plane. In
// layer mode the ground is the parabolic Earth (altitude 0), tessellated finely on the GPU.
void scene_hit(CpuShader& sh, const ref::CloudParams& P, const dvec3& rd, double& t_scene, dvec3& scene_color) {
  t_scene = CV_NO_HIT;
  scene_color = dvec3(0.0);
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
}

struct Lookups {
  std::shared_ptr<const AtmosphereLuts> shared;
  const AtmosphereLuts& lut;
  AirTexels air;  // render.air_lut: this frame's (the camera's altitude and the sun are the frame's)
  explicit Lookups(const FrameSetup& frame)
      : shared(int(frame.params.sky_mode) == CV_SKY_PRECOMPUTED ? shared_atmosphere_luts(frame.settings.atmosphere)
                                                                 : nullptr),
        lut(shared ? *shared : no_lut()) {}
};

// Bloom (half-resolution bright pass, separable Gaussian, added before tone mapping) and the tone
// map: the same passes and taps as bloom_bright.glsl, bloom_blur.glsl, tonemap.glsl.
FrameImages finish(const PreparedVolume& vol, const FrameSetup& frame, const AtmosphereLuts& lut, const Buffer& hdr) {
  const int w = frame.width, h = frame.height;
  const ref::CloudParams& P = frame.params;
  const double exposure = frame.settings.exposure, strength = frame.settings.bloom;
  const double threshold = frame.settings.bloom_threshold;
  const int op = int(frame.settings.tonemap);
  const int bw = std::max(1, w / 2), bh = std::max(1, h / 2);
  Buffer bright(bw, bh), blur_h(bw, bh), blur_v(bw, bh);
  CpuShader sh(P, vol, lut);
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

}  // namespace

FrameImages render_cpu(const PreparedVolume& vol, const FrameSetup& frame) {
  const int w = frame.width, h = frame.height;
  const ref::CloudParams& P = frame.params;
  Lookups look(frame);
  Buffer hdr(w, h);
  // The light volume, when on: the same texels the light_volume pass computes, in double precision.
  std::vector<double> light_volume;
  if (P.light_volume_on > 0.5) light_volume = build_light_volume_cpu(vol, P, &frame);
  // The diffusion volume, when on: the same cells the ms_source pass computes, the same solver.
  std::vector<dvec4> ms_volume;
  if (P.ms_volume_on > 0.5) {
    const MsDiffusionOptions o = ms_diffusion_options(P, frame.mie);
    ms_volume = ms_volume_texels(
        solve_ms_diffusion(build_ms_source_cpu(vol, P, P.light_volume_on > 0.5 ? &light_volume : nullptr), o),
        o.asymmetry);
  }
  // The ground shadow map, when on: the texels the shadow_map pass computes, in double precision.
  std::vector<double> shadow_map;
  if (P.shadow_map_on > 0.5) shadow_map = build_shadow_map_cpu(vol, frame);
  tbb::parallel_for(0, h, [&](int y) {
    CpuShader sh(P, vol, look.lut, &frame);
    sh.air = &look.air;
    sh.light_volume = &light_volume;
    sh.shadow_map = &shadow_map;
    sh.ms_volume = &ms_volume;
    for (int x = 0; x < w; ++x) {
      dvec3 rd = sh.pixel_ray(frame.inv_view_proj, dvec2(x + 0.5, y + 0.5), dvec2(w, h));
      double t_scene;
      dvec3 scene_color;
      scene_hit(sh, P, rd, t_scene, scene_color);
      hdr.at(x, y) = sh.compose_pixel(rd, ivec2(x, y), t_scene, scene_color);
    }
  });
  return finish(vol, frame, look.lut, hdr);
}


// ------------------------------------------------------------------------------ path tracer
//
// The ground truth for the lighting (`--backend pathtrace`): unbiased Monte Carlo transport through
// the same medium (CpuShader::cloud_density: the same texture, placement, erosion, coverage and
// motion as both renderers), every order of scattering. Delta tracking samples the collisions
// against a majorant (the largest base-shape value times the density and extinction scales:
// erosion, coverage and the cloud-type gradient only lower the density), next-event estimation
// with ratio tracking adds the sun at every collision, the phase function is sampled (HG
// analytically, the Mie table by its tabulated CDF) and a path that leaves the medium sees the
// marcher's ambient light: the sky's (ambient_color) upwards, the ground and air's
// (ambient_below_color) downwards (the marcher mixes the two by height, an approximation this
// measures). A camera ray that crosses the medium without a
// collision sees the marcher's background (sky, ground with its cloud shadows, air), and the
// light of a collided path is faded by the same aerial perspective at its first collision.
// References: Woodcock et al. 1965 (delta tracking), Novak et al., "Monte Carlo Methods for Volumetric
// Light Transport Simulation", Eurographics STAR 2018 (ratio tracking, NEE).
namespace {

// PCG32 (O'Neill 2014), its seed scrambled by SplitMix64 first: the path tracer's keys put the
// pixel, the seed and the sample index in separate bit ranges, and with one fixed increment such
// seeds give streams whose states share their low bits forever (two images of different seeds
// came out correlated: their RMSE was half what their standard errors implied).
inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
struct Pcg32 {
  uint64_t state;
  explicit Pcg32(uint64_t seed) : state(splitmix64(seed) * 6364136223846793005ull + 1442695040888963407ull) { next(); }
  uint32_t next() {
    uint64_t old = state;
    state = old * 6364136223846793005ull + 1442695040888963407ull;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  double uniform() { return (next() >> 8) * (1.0 / 16777216.0); }  // [0, 1)
};

// Sampling the phase function: HG analytically; the Mie table by the piecewise-constant CDF of its
// green channel's p(theta) sin(theta) over its bins, each channel weighted by its phase / pdf so the
// estimate stays unbiased (red and blue differ from green by at most 1.5x, at the forward peak); the
// two-lobe HG by its two HG lobes and the HG + Draine fit by its HG lobe and Draine's lobe, each
// lobe exactly (Draine's by its inverse CDF, cloudgen::phase::sample_draine), so their weight is 1.
struct PhaseSampler {
  int mode = CV_PHASE_HG;
  double g = 0;
  double lobe_g[2] = {0, 0}, lobe_w = 1;  // two lobes: w HG(g0) + (1 - w) HG(g1) or Draine(g1, alpha)
  double draine_alpha = 0;
  std::vector<double> cdf;   // Mie: per bin, cumulative probability
  std::vector<double> mass;  // Mie: probability of each bin
  int bins = 0;
  PhaseSampler(const ref::CloudParams& p, const std::shared_ptr<const MiePhaseTable>& table)
      : mode(int(p.phase_mode)), g(p.hg_g) {
    if (mode == CV_PHASE_TWO_LOBE_HG) lobe_g[0] = p.hg_g, lobe_g[1] = p.hg_g2, lobe_w = p.lobe_weight;
    if (mode == CV_PHASE_DRAINE_HG)
      lobe_g[0] = p.draine_g_hg, lobe_g[1] = p.draine_g_d, lobe_w = 1 - p.draine_w_d, draine_alpha = p.draine_alpha;
    if (mode != CV_PHASE_MIE) return;
    const MiePhaseTable& mie = table ? *table : *computed_mie_table();
    bins = mie.size() - 1;
    double total = 0;
    for (int i = 0; i < bins; ++i) {
      double a = M_PI * i / bins, b = M_PI * (i + 1) / bins;
      double m = 0.5 * (mie.at(i, 1) + mie.at(i + 1, 1)) * (std::cos(a) - std::cos(b));
      mass.push_back(m);
      total += m;
    }
    double c = 0;
    for (double& m : mass) {
      m /= total;
      c += m;
      cdf.push_back(c);
    }
  }
  // A new direction around unit d (cos of the angle to d = the scattering cosine), and the weight
  // per colour channel.
  dvec3 sample(CpuShader& sh, const dvec3& d, Pcg32& rng, dvec3& weight) const {
    double u1 = rng.uniform(), u2 = rng.uniform();
    double cos_t;
    weight = dvec3(1.0);
    auto hg_sample = [](double gg, double u) {
      if (std::abs(gg) <= 1e-4) return 1 - 2 * u;
      const double q = (1 - gg * gg) / (1 - gg + 2 * gg * u);
      return std::clamp((1 + gg * gg - q * q) / (2 * gg), -1.0, 1.0);
    };
    if (mode == CV_PHASE_HG && std::abs(g) > 1e-4) {
      cos_t = hg_sample(g, u1);
    } else if (mode == CV_PHASE_TWO_LOBE_HG) {
      cos_t = hg_sample(u1 < lobe_w ? lobe_g[0] : lobe_g[1], rng.uniform());
      const double pdf = lobe_w * sh.lobe_hg(lobe_g[0], cos_t) + (1 - lobe_w) * sh.lobe_hg(lobe_g[1], cos_t);
      weight = dvec3(sh.phase_function(cos_t) / pdf);
    } else if (mode == CV_PHASE_DRAINE_HG) {
      // The mixture's own lobes, each sampled exactly: the pdf is the phase function, weight 1.
      cos_t = u1 < lobe_w ? hg_sample(lobe_g[0], rng.uniform()) : cloudgen::phase::sample_draine(lobe_g[1], draine_alpha, rng.uniform());
    } else if (mode == CV_PHASE_MIE) {
      int i = int(std::lower_bound(cdf.begin(), cdf.end(), u1) - cdf.begin());
      i = std::min(i, bins - 1);
      double ca = std::cos(M_PI * i / bins), cb = std::cos(M_PI * (i + 1) / bins);
      cos_t = cb + (ca - cb) * u2;
      u2 = rng.uniform();
      double pdf = mass[size_t(i)] / (2 * M_PI * (ca - cb));
      weight = sh.phase_function_rgb(cos_t) / pdf;
    } else {
      cos_t = 1 - 2 * u1;
    }
    double sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
    double phi = 2 * M_PI * u2;
    dvec3 a = std::abs(d.x) < 0.9 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
    dvec3 t = glm::normalize(glm::cross(d, a)), b = glm::cross(d, t);
    return glm::normalize(d * cos_t + (t * std::cos(phi) + b * std::sin(phi)) * sin_t);
  }
};

struct PathTracer {
  CpuShader& sh;
  const ref::CloudParams& P;
  const PhaseSampler& phase;
  double majorant;  // 1/m
  int max_scatterings;

  dvec2 interval(const dvec3& o, const dvec3& d) {
    if (sh.layer_mode()) return sh.shell_interval(o, d);
    dvec3 bmin = P.march_min_m - o;
    return sh.ray_box(d, bmin, bmin + P.march_size_m);
  }
  double sigma(const dvec3& x) { return sh.cloud_density(x) * P.sigma_t_per_m; }
  // Delta tracking in [t0, t1): the first real collision, or false.
  bool collide(const dvec3& o, const dvec3& d, double t0, double t1, Pcg32& rng, double& t_hit) {
    if (!(t1 > t0) || majorant <= 0) return false;
    double t = t0;
    for (;;) {
      t -= std::log(1.0 - rng.uniform()) / majorant;
      if (t >= t1) return false;
      if (rng.uniform() * majorant < sigma(o + d * t)) {
        t_hit = t;
        return true;
      }
    }
  }
  // Ratio tracking toward the sun, with Russian roulette once the estimate is small.
  double transmittance(const dvec3& x, const dvec3& d, Pcg32& rng) {
    dvec2 tb = interval(x, d);
    if (!(tb.y > tb.x) || majorant <= 0) return 1.0;
    double T = 1.0, t = std::max(tb.x, 0.0);
    for (;;) {
      t -= std::log(1.0 - rng.uniform()) / majorant;
      if (t >= tb.y) return T;
      T *= std::max(0.0, 1.0 - sigma(x + d * t) / majorant);
      if (T < 0.05) {
        if (rng.uniform() < 0.5) return 0.0;
        T *= 2.0;
      }
    }
  }
  dvec3 radiance(const dvec3& rd, Pcg32& rng) {
    double t_scene;
    dvec3 scene_color;
    scene_hit(sh, P, rd, t_scene, scene_color);
    dvec2 tb = interval(dvec3(0.0), rd);
    double t1 = std::min(tb.y, std::min(t_scene, P.max_distance_m));
    double t_first = 0;
    if (!collide(dvec3(0.0), rd, std::max(tb.x, 0.0), t1, rng, t_first))
      return sh.compose_over(dvec4(0.0, 0.0, 0.0, 1.0), rd, t_scene, scene_color);
    const dvec3 sun = P.sun_dir;
    const dvec3 ambient_above = P.ambient_color * P.ambient_scale, ambient_below = P.ambient_below_color * P.ambient_scale;
    dvec3 L(0.0), throughput(1.0);
    dvec3 x = rd * t_first, d = rd;
    for (int n = 0; n < max_scatterings; ++n) {
      if (P.sun_radiance > 0)
        L += throughput * P.albedo * sh.sun_color_at(x) *
             sh.phase_function_rgb(glm::dot(d, sun)) * (P.sun_radiance * transmittance(x, sun, rng));
      throughput *= P.albedo;
      double m = std::max(throughput.x, std::max(throughput.y, throughput.z));
      if (m < 0.1) {  // Russian roulette
        if (rng.uniform() > m) break;
        throughput /= m;
      }
      dvec3 w(1.0);
      dvec3 next = phase.sample(sh, d, rng, w);
      throughput *= w;
      dvec2 nb = interval(x, next);
      double s = 0;
      if (!collide(x, next, std::max(nb.x, 0.0), nb.y, rng, s)) {
        L += throughput * (next.y >= 0 ? ambient_above : ambient_below);
        break;
      }
      x += next * s;
      d = next;
    }
    if (int(P.output_mode) == CV_OUTPUT_TRANSMITTANCE) return dvec3(0.0);
    return dvec3(sh.aerial_perspective(dvec4(L, 0.0), t_first, rd));
  }
};

double majorant_of(const PreparedVolume& vol, const ref::CloudParams& P) {
  double m = 0;
  for (size_t i = 0; i < vol.rgba.size(); i += 4) m = std::max(m, double(vol.rgba[i]));
  if (vol.nano) {  // the density grid's root statistics (1 when absent: cloudgen's densities are <= 1)
    CpuShader sh(P, vol, no_lut());
    pnanovdb_buf_t buf = sh.nvdb_buf();
    pnanovdb_root_handle_t root = sh.nvdb_root(buf, 0);
    double stat = pnanovdb_read_float(buf, pnanovdb_root_get_max_address(PNANOVDB_GRID_TYPE_FLOAT, buf, root));
    m = std::max(std::isfinite(stat) ? stat : 0.0, 1.0);
  }
  return m * std::max(P.density_scale, 0.0) * P.sigma_t_per_m;
}

}  // namespace

glm::dvec3 pathtrace_ray(const PreparedVolume& vol, const FrameSetup& frame, const glm::dvec3& rd, int spp,
                         uint32_t seed) {
  Lookups look(frame);
  CpuShader sh(frame.params, vol, look.lut, &frame);
  sh.air = &look.air;
  PhaseSampler phase(frame.params, frame.mie);
  PathTracer pt{sh, frame.params, phase, majorant_of(vol, frame.params), 4096};
  dvec3 sum(0.0);
  for (int i = 0; i < spp; ++i) {
    Pcg32 rng((uint64_t(seed) << 32) ^ uint64_t(i) * 0x9E3779B97F4A7C15ull);
    sum += pt.radiance(glm::normalize(rd), rng);
  }
  return sum / double(std::max(spp, 1));
}

FrameImages render_pathtrace(const PreparedVolume& vol, const FrameSetup& frame, const PathTraceOptions& o) {
  const int w = frame.width, h = frame.height;
  ref::CloudParams P = frame.params;
  P.shadow_map_on = 0;  // the reference marches the ground's shadow per point (render.shadow_map is a speed knob)
  Lookups look(frame);
  PhaseSampler phase(P, frame.mie);
  const double majorant = majorant_of(vol, P);
  Buffer hdr(w, h);
  if (o.standard_error) *o.standard_error = Image(w, h);
  std::vector<dvec3> sums(o.sum ? size_t(w) * h : 0);  // this call's per-pixel sums, for o.sum
  std::atomic<int> rows_done{0};
  tbb::parallel_for(0, h, [&](int y) {
    if (o.cancel && o.cancel->load()) return;
    CpuShader sh(P, vol, look.lut, &frame);
    sh.air = &look.air;
    PathTracer pt{sh, P, phase, majorant, o.max_scatterings};
    for (int x = 0; x < w; ++x) {
      dvec3 rd = sh.pixel_ray(frame.inv_view_proj, dvec2(x + 0.5, y + 0.5), dvec2(w, h));
      dvec3 sum(0.0), sum2(0.0);
      for (int i = o.first_sample; i < o.first_sample + o.spp; ++i) {  // one stream per pixel and sample: any thread count, same image
        uint64_t key = (uint64_t(uint32_t(y * w + x)) << 32) ^ (uint64_t(o.seed) << 20) ^ uint64_t(i);
        Pcg32 rng(key);
        const dvec3 l = pt.radiance(rd, rng);
        sum += l, sum2 += l * l;
      }
      const double n = double(std::max(o.spp, 1));
      hdr.at(x, y) = sum / n;
      if (o.sum) sums[size_t(y) * w + x] = sum;
      if (o.standard_error) {
        const dvec3 mean = sum / n;
        const dvec3 var = n > 1 ? glm::max(sum2 / n - mean * mean, dvec3(0.0)) * (n / (n - 1)) : dvec3(0.0);
        const dvec3 se = glm::sqrt(var / n);
        float* px = o.standard_error->at(x, y);
        px[0] = float(se.x), px[1] = float(se.y), px[2] = float(se.z), px[3] = 1.f;
      }
    }
    int done = ++rows_done;
    if (o.progress) o.progress(done, h);
  });
  if (o.cancel && o.cancel->load()) return {};
  if (o.sum) {
    PathTraceSum& acc = *o.sum;
    if (acc.width != w || acc.height != h) acc = PathTraceSum{w, h, std::vector<double>(size_t(w) * h * 3, 0.0), 0};
    acc.paths += o.spp;
    const double n = double(std::max<int64_t>(acc.paths, 1));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double* a = &acc.rgb[(size_t(y) * w + x) * 3];
        const dvec3& add = sums[size_t(y) * w + x];
        a[0] += add.x, a[1] += add.y, a[2] += add.z;
        hdr.at(x, y) = dvec3(a[0], a[1], a[2]) / n;
      }
  }
  return finish(vol, frame, look.lut, hdr);
}

}  // namespace cloudviewer
