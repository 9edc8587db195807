// OpenGL 4.5 deferred renderer: ground pass (HDR + distance), full-screen cloud pass, bloom
// (half resolution, separable Gaussian), tone map + sRGB, declared as a table of targets and passes.
// GPU timer queries around every pass.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include "cloudgen/motion.h"
#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/constants.h"
#include "cloudviewer/detail_texture.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"
#include "cloudgen/nvdb.h"

namespace cloudviewer {
namespace {

GLuint make_texture_2d(GLenum internal, int w, int h) {
  GLuint t;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, internal, w, h);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

void check_fbo(GLuint fbo, const char* what) {
  GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw GlError(std::string("framebuffer '") + what + "' incomplete (status 0x" + std::to_string(status) + ")");
}

// Links compiled stages into a program (deleting the stages); `what` names them in the error.
GLuint link_stages(std::initializer_list<GLuint> stages, const std::string& what, const std::string& file) {
  GLuint p = glCreateProgram();
  for (GLuint st : stages) glAttachShader(p, st);
  glLinkProgram(p);
  for (GLuint st : stages) glDeleteShader(st);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetProgramInfoLog(p, sizeof(log), nullptr, log);
    glDeleteProgram(p);
    throw ShaderError("shader link error (" + what + "):\n" + log, file, 0);
  }
  return p;
}

GLuint link_program(const ShaderSource& src, const std::string& vs, const std::string& fs) {
  GLuint v = compile_shader_stage(GL_VERTEX_SHADER, src, vs);
  GLuint f = 0;
  try {
    f = compile_shader_stage(GL_FRAGMENT_SHADER, src, fs);
  } catch (...) {
    glDeleteShader(v);
    throw;
  }
  return link_stages({v, f}, vs + " + " + fs, fs);
}

// render.compute: a pass's compute shader alone.
GLuint link_compute_program(const ShaderSource& src, const std::string& cs) {
  return link_stages({compile_shader_stage(GL_COMPUTE_SHADER, src, cs)}, cs, cs);
}

// modes.glsl's switches baked into the GL programs (render.compiled_modes): one row per CV_MODE_*
// macro, the value the frame's CloudParams give it. A macro modes.glsl declares and this table
// lacks is an undeclared identifier in every cloud program, so the two cannot drift apart silently.
struct ModeRow {
  const char* macro;
  double (*value)(const ref::CloudParams&);
};
const ModeRow kModes[] = {
    {"CV_MODE_LAYER", [](const ref::CloudParams& p) { return p.layer_on; }},
    {"CV_MODE_MOTION", [](const ref::CloudParams& p) { return p.motion_on; }},
    {"CV_MODE_TILES", [](const ref::CloudParams& p) { return p.tiles_xz; }},
    {"CV_MODE_EXACT_FILTER", [](const ref::CloudParams& p) { return p.exact_filter; }},
    {"CV_MODE_DETAIL", [](const ref::CloudParams& p) { return p.has_detail; }},
    {"CV_MODE_CURL", [](const ref::CloudParams& p) { return p.curl_amplitude_m > 0.0 ? 1.0 : 0.0; }},
    {"CV_MODE_FINE_DETAIL", [](const ref::CloudParams& p) { return p.fine_detail_strength > 0.0 ? 1.0 : 0.0; }},
    {"CV_MODE_LIGHT", [](const ref::CloudParams& p) { return p.light_mode; }},
    {"CV_MODE_DF_LIGHT", [](const ref::CloudParams& p) { return p.df_light; }},
    {"CV_MODE_LIGHT_VOLUME", [](const ref::CloudParams& p) { return p.light_volume_on; }},
    {"CV_MODE_SHADOW_MAP", [](const ref::CloudParams& p) { return p.shadow_map_on; }},
    {"CV_MODE_MS_VOLUME", [](const ref::CloudParams& p) { return p.ms_volume_on; }},
    {"CV_MODE_MS_OCTAVES", [](const ref::CloudParams& p) { return p.ms_octaves; }},
    {"CV_MODE_PHASE", [](const ref::CloudParams& p) { return p.phase_mode; }},
    {"CV_MODE_SKY", [](const ref::CloudParams& p) { return p.sky_mode; }},
    {"CV_MODE_SKY_LUT", [](const ref::CloudParams& p) { return p.sky_lut; }},
    {"CV_MODE_AIR_LUT", [](const ref::CloudParams& p) { return p.air_lut; }},
    {"CV_MODE_OUTPUT", [](const ref::CloudParams& p) { return p.output_mode; }},
    {"CV_MODE_ADAPTIVE", [](const ref::CloudParams& p) { return p.adaptive; }},
    {"CV_MODE_SKIP", [](const ref::CloudParams& p) { return p.occupancy_skip; }},
    {"CV_MODE_SKIP_DISTANCE", [](const ref::CloudParams& p) { return p.skip_distance; }},
    {"CV_MODE_SKIP_TREE", [](const ref::CloudParams& p) { return p.skip_tree; }},
    {"CV_MODE_DENSITY_STEP", [](const ref::CloudParams& p) { return p.density_step; }},
};

// The text that replaces modes.glsl for a frame: each macro a float constant (the value rounded
// to float, as the uniform block holds it).
std::string compiled_modes_text(const ref::CloudParams& p) {
  std::string text = "// modes.glsl compiled for one frame's modes (gl_renderer.cpp, kModes)\n";
  for (const ModeRow& row : kModes) {
    char value[64];
    std::snprintf(value, sizeof(value), "%.9g", double(float(row.value(p))));
    std::string v = value;
    if (v.find_first_of(".en") == std::string::npos) v += ".0";
    text += std::string("#define ") + row.macro + " (" + v + ")\n";
  }
  return text;
}

// Render targets and passes are declared in two tables (make_targets, make_passes); resize() and
// render() walk them. A new pass (a sky LUT precompute, a temporal resolve) is one more entry:
//  - a Target sized by the viewport (divisor 1 or 2) or fixed (a LUT: `fixed_w`/`fixed_h`), with
//    `history` to keep last frame's copy readable as "NAME@prev" (swapped after every frame);
//  - a Pass naming its program, the target it writes, the attachments it reads (bound in order to
//    CV_UNIT_PASS_INPUT0 .. 5), when it runs, and its timing group.
struct Target {
  std::string name;
  std::vector<GLenum> colors;  // internal format of each colour attachment
  bool depth = false;
  int divisor = 1;             // viewport / divisor (at least 1 pixel)
  bool round_up = false;       // ceil(viewport / divisor): every pixel has its block (temporal)
  int fixed_w = 0, fixed_h = 0;  // > 0: a fixed size (LUTs), independent of the viewport
  bool history = false;        // keep the previous frame's copy ("NAME@prev")
  int linear_from = -1;        // >= 0: attachments from this one on filter linearly (read with texture())
  // A 3D target sized by the frame (the light volume: f.params.light_volume_dims) or fixed (the 4D
  // scattering LUT), one 3D texture per colour attachment; its passes draw once per layer, into
  // that layer of every attachment. (Re)created by render() when the size changes.
  std::function<glm::ivec3(const FrameSetup&)> volume_size;
  int d = 0;
  // GL objects: [0] the current frame, [1] the previous one when `history`.
  int w = 0, h = 0;
  GLuint fbo[2] = {0, 0};
  std::vector<GLuint> tex[2];
  GLuint depth_tex[2] = {0, 0};
};

enum class Group { Atmosphere, Light, Shadow, Ground, Clouds, Post };

struct Pass {
  std::string name;
  std::string vs, fs;
  std::string cs;                                    // render.compute: the same pass as a compute shader
                                                     // (one invocation per texel of its target)
  bool compute = false;                              // its program is the compute one (build_programs)
  int cs_outputs = -1;                               // compute: its target's first attachments it stores (-1: all)
  std::string target;
  std::vector<std::pair<std::string, int>> inputs;  // (target, attachment) -> CV_UNIT_PASS_INPUT0 + i
  Group group = Group::Post;
  bool mesh = false;                                 // the ground mesh instead of a full-screen triangle
  std::vector<std::array<float, 4>> clear;           // per colour attachment; empty = no clear
  std::function<bool(const FrameSetup&)> enabled;    // null = always
  std::function<void(GLuint program)> uniforms;      // per-pass uniforms, null = none
  bool precompute = false;                           // an atmosphere LUT: runs only when atmosphere.* changed
  std::vector<int> lut_units;                        // precompute: the unit of each attachment, for later passes
  bool lut_valid = false;                            // precompute: its target holds the current atmosphere's LUT
  int runs = 0;                                      // precompute: how many times it has run
  bool light_volume = false;                         // runs only when the light volume's inputs changed
  bool shadow_map = false;                           // runs only when the ground shadow map's inputs changed
  bool ms_volume = false;                            // runs only when the diffusion volume's inputs changed
  bool air_lut = false;                              // runs only when the air LUT's inputs changed
  bool orders_loop = false;                          // precompute: the density orders' loop follows it
  bool driven = false;                               // run by the orders loop, not by the frame's walk
  int blend_attachment = -1;                         // a 3D target's attachment this pass adds into
  int history_held = -1;                             // temporal: 1 runs only when the history is held
                                                     // (nothing moved), 0 only when not; -1 either way
  std::vector<std::pair<std::string, int>> images;  // (target, attachment) -> CV_IMAGE_PASS_OUTPUT0 + i,
                                                     // written with imageStore (its own target's copy)
  bool drew = false;                                 // run() drew it this frame (GpuTimings::passes)
  GLuint program = 0;
};

std::vector<Target> make_targets() {
  std::vector<Target> t(8);
  t[0].name = "scene", t[0].colors = {GL_RGBA32F, GL_R32F}, t[0].depth = true;  // ground radiance, distance
  t[1].name = "hdr", t[1].colors = {GL_RGBA32F};                                 // clouds over the scene
  t[2].name = "bloom_a", t[2].colors = {GL_RGBA32F}, t[2].divisor = 2;
  t[3].name = "bloom_b", t[3].colors = {GL_RGBA32F}, t[3].divisor = 2;
  t[4].name = "final", t[4].colors = {GL_RGBA32F, GL_RGBA32F};                 // display, linear
  t[5].name = "transmittance", t[5].colors = {GL_RGBA32F};                        // atmosphere LUT T(r, mu)
  t[5].fixed_w = CV_TRANSMITTANCE_W, t[5].fixed_h = CV_TRANSMITTANCE_H;
  t[5].linear_from = 0;  // sun_color_at reads it filtered (texelFetch elsewhere)
  // Temporal upsampling: this frame's pixel of every 4x4 block, and the resolved full-resolution
  // cloud layer with last frame's copy (both: (L, T) and the cloud distance).
  // The quarter target also holds the air in front of the background at the same pixels: toward
  // the ground (extinction and in-scattering per metre) and toward the sky (inscattered), each
  // with its weight; temporal_compose filters them bilinearly.
  t[6].name = "cloud_quarter", t[6].colors = {GL_RGBA32F, GL_R32F, GL_RGBA32F, GL_RGBA32F, GL_RGBA32F};
  t[6].divisor = 4, t[6].round_up = true, t[6].linear_from = 2;
  t[7].name = "cloud_layer", t[7].colors = {GL_RGBA32F, GL_R32F}, t[7].history = true;
  Target ms;     // atmosphere LUT Psi_ms(r, mu_s): orders 2..N of the sky's scattering
  ms.name = "multiple_scattering", ms.colors = {GL_RGBA32F};
  ms.fixed_w = CV_MS_LUT_SIZE, ms.fixed_h = CV_MS_LUT_SIZE;
  t.push_back(ms);
  Target irradiance;  // atmosphere LUT E(mu_s): the sky's irradiance on the ground
  irradiance.name = "irradiance", irradiance.colors = {GL_RGBA32F};
  irradiance.fixed_w = CV_IRRADIANCE_W, irradiance.fixed_h = 1;
  t.push_back(irradiance);
  Target light;  // optical depth toward the sun over the box (render.light_volume)
  light.name = "light_volume", light.colors = {GL_R32F};
  light.volume_size = [](const FrameSetup& f) { return glm::ivec3(f.params.light_volume_dims); };
  t.push_back(light);
  Target shadow;  // the ground's cloud shadow (render.shadow_map): one layer, sized by the frame
  shadow.name = "shadow_map", shadow.colors = {GL_R32F};
  shadow.volume_size = [](const FrameSetup& f) {
    return glm::ivec3(int(f.params.shadow_map_nx), int(f.params.shadow_map_nz), 1);  // (0, 0) when off: 1 texel
  };
  t.push_back(shadow);
  Target ms_source;  // the diffusion volume's inputs per cell: mean sigma_t, mean sigma_t * T_sun
  ms_source.name = "ms_source", ms_source.colors = {GL_RG32F};
  ms_source.volume_size = [](const FrameSetup& f) { return glm::ivec3(f.params.ms_volume_dims); };
  t.push_back(ms_source);
  Target air;  // the camera's air LUT (render.air_lut): Rayleigh with the orders folded in, Mie
  air.name = "air", air.colors = {GL_RGBA32F, GL_RGBA32F};
  air.volume_size = [](const FrameSetup&) { return glm::ivec3(CV_AIR_AZIMUTH, CV_AIR_ELEVATION, CV_AIR_DEPTH); };
  t.push_back(air);
  Target scattering;  // atmosphere LUT S(r, mu, mu_s, nu): single Rayleigh, single Mie, orders 2..N
  scattering.name = "scattering", scattering.colors = {GL_RGBA32F, GL_RGBA32F, GL_RGBA32F};
  scattering.volume_size = [](const FrameSetup&) {
    return glm::ivec3(CV_SCATTERING_NU * CV_SCATTERING_MU_S, CV_SCATTERING_MU, CV_SCATTERING_R);
  };
  t.push_back(scattering);
  // atmosphere.density_orders: the orders table's parts (atmosphere.glsl, orders_dims).
  auto orders_size = [](const FrameSetup&) { return glm::ivec3(kOrdersNX, kOrdersNY, kOrdersNZ); };
  Target single;  // single Rayleigh, single Mie
  single.name = "orders_single", single.colors = {GL_RGBA32F, GL_RGBA32F}, single.volume_size = orders_size;
  t.push_back(single);
  Target density;  // J of the order being computed: its Rayleigh and Mie angular integrals
  density.name = "orders_density", density.colors = {GL_RGBA32F, GL_RGBA32F}, density.volume_size = orders_size;
  t.push_back(density);
  Target delta;  // the last order's light, and the orders 2..N summed
  delta.name = "orders_delta", delta.colors = {GL_RGBA32F, GL_RGBA32F}, delta.volume_size = orders_size;
  t.push_back(delta);
  Target orders_irradiance;  // the last order's irradiance on the ground
  orders_irradiance.name = "orders_irradiance", orders_irradiance.colors = {GL_RGBA32F};
  orders_irradiance.fixed_w = CV_IRRADIANCE_W, orders_irradiance.fixed_h = 1;
  t.push_back(orders_irradiance);
  return t;
}

// Temporal upsampling runs for the radiance and transmittance outputs (the loop-trip output needs
// every pixel's own march).
bool temporal_on(const FrameSetup& f) { return f.settings.temporal && f.settings.output != OutputMode::Iterations; }

std::vector<Pass> make_passes() {
  auto bloom_on = [](const FrameSetup& f) { return f.settings.bloom > 0; };
  std::vector<Pass> p;
  // Atmosphere LUTs (atmosphere.glsl), recomputed only when an atmosphere.* key changes.
  Pass transmittance;
  transmittance.name = "atmosphere_transmittance", transmittance.vs = "fullscreen.vert";
  transmittance.fs = "atmosphere_transmittance.frag", transmittance.target = "transmittance";
  transmittance.group = Group::Atmosphere, transmittance.precompute = true;
  transmittance.lut_units = {CV_UNIT_TRANSMITTANCE};
  p.push_back(transmittance);
  Pass multiple;  // reads the transmittance LUT
  multiple.name = "atmosphere_multiple_scattering", multiple.vs = "fullscreen.vert";
  multiple.fs = "atmosphere_multiple_scattering.frag", multiple.target = "multiple_scattering";
  multiple.group = Group::Atmosphere, multiple.precompute = true;
  multiple.lut_units = {CV_UNIT_MULTIPLE_SCATTERING};
  p.push_back(multiple);
  Pass irradiance;  // reads both LUTs before it
  irradiance.name = "atmosphere_irradiance", irradiance.vs = "fullscreen.vert";
  irradiance.fs = "atmosphere_irradiance.frag", irradiance.target = "irradiance";
  irradiance.group = Group::Atmosphere, irradiance.precompute = true;
  irradiance.lut_units = {CV_UNIT_IRRADIANCE};
  p.push_back(irradiance);
  // atmosphere.density_orders (with render.sky_lut): the orders table's single parts, then the
  // loop of orders 2..N (run_orders: density, ground irradiance, light of each order, summed),
  // which the 4D LUT's pass reads.
  auto density_on = [](const FrameSetup& f) {
    return f.params.sky_lut > 0.5 && f.settings.atmosphere.density_orders && f.settings.atmosphere.scattering_orders > 1;
  };
  Pass orders;
  orders.name = "atmosphere_orders", orders.vs = "fullscreen.vert", orders.fs = "atmosphere_orders_single.frag";
  orders.target = "orders_single", orders.group = Group::Atmosphere, orders.precompute = true;
  orders.lut_units = {CV_UNIT_ORDERS_SINGLE_R, CV_UNIT_ORDERS_SINGLE_M};
  orders.enabled = density_on, orders.orders_loop = true;
  p.push_back(orders);
  const char* order_passes[][3] = {{"atmosphere_orders_density", "atmosphere_orders_density.frag", "orders_density"},
                                   {"atmosphere_orders_irradiance", "atmosphere_orders_irradiance.frag", "orders_irradiance"},
                                   {"atmosphere_orders_multiple", "atmosphere_orders_multiple.frag", "orders_delta"}};
  for (auto& o : order_passes) {
    Pass d;
    d.name = o[0], d.vs = "fullscreen.vert", d.fs = o[1], d.target = o[2];
    d.group = Group::Atmosphere, d.driven = true;
    if (d.target == "orders_delta") d.blend_attachment = 1;
    p.push_back(d);
  }
  // Bruneton's 4D scattering LUT (reads the transmittance and multiple-scattering LUTs), only for
  // render.sky_lut: it is 96 MiB and seconds of llvmpipe time.
  Pass scattering;
  scattering.name = "atmosphere_scattering", scattering.vs = "fullscreen.vert";
  scattering.fs = "atmosphere_scattering.frag", scattering.target = "scattering";
  scattering.group = Group::Atmosphere, scattering.precompute = true;
  scattering.lut_units = {CV_UNIT_SCATTERING, CV_UNIT_SINGLE_MIE, CV_UNIT_SCATTERING_MULTIPLE};
  scattering.enabled = [](const FrameSetup& f) { return f.params.sky_lut > 0.5; };
  p.push_back(scattering);
  // The camera's air LUT (reads the LUTs above), rebuilt when the sun, the camera's altitude or the
  // atmosphere changes; the cloud passes read it.
  Pass air;
  air.name = "air_lut", air.vs = "fullscreen.vert", air.fs = "air_lut.frag", air.target = "air";
  air.group = Group::Atmosphere, air.air_lut = true;
  air.enabled = [](const FrameSetup& f) { return f.params.air_lut > 0.5; };
  p.push_back(air);
  // The ground's cloud shadow (lighting.glsl ground_shadow), rebuilt only when the sun, the volume,
  // the time or a lighting key changes; the ground pass reads it. Timed apart (shadow_map_ms), as
  // the light volume is: with still clouds and sun it is paid once; moving clouds pay it every frame.
  Pass shadow;
  shadow.name = "shadow_map", shadow.vs = "fullscreen.vert", shadow.fs = "shadow_map.frag";
  shadow.target = "shadow_map", shadow.group = Group::Shadow, shadow.shadow_map = true;
  shadow.enabled = [](const FrameSetup& f) { return f.params.shadow_map_on > 0.5; };
  p.push_back(shadow);
  Pass ground;
  ground.name = "ground", ground.vs = "ground.vert", ground.fs = "ground.frag", ground.target = "scene";
  ground.group = Group::Ground, ground.mesh = true, ground.inputs = {{"shadow_map", 0}};
  ground.clear = {{0.f, 0.f, 0.f, 0.f}, {float(CV_NO_HIT), 0.f, 0.f, 0.f}};
  ground.enabled = [](const FrameSetup& f) { return f.params.ground_on > 0.5; };
  p.push_back(ground);
  // The light volume (lighting.glsl), rebuilt only when the sun, the volume or a lighting key changes.
  Pass light;
  light.name = "light_volume", light.vs = "fullscreen.vert", light.fs = "light_volume.frag";
  light.target = "light_volume", light.group = Group::Light, light.light_volume = true;
  light.enabled = [](const FrameSetup& f) { return f.params.light_volume_on > 0.5; };
  p.push_back(light);
  // The diffusion volume's inputs (after the light volume, which they read); the renderer solves
  // the diffusion on the CPU from them and uploads the fluence (render.ms_volume).
  Pass ms;
  ms.name = "ms_volume", ms.vs = "fullscreen.vert", ms.fs = "ms_source.frag";
  ms.target = "ms_source", ms.group = Group::Light, ms.ms_volume = true;
  ms.enabled = [](const FrameSetup& f) { return f.params.ms_volume_on > 0.5; };
  p.push_back(ms);
  auto temporal = [](const FrameSetup& f) { return temporal_on(f); };
  Pass clouds;
  clouds.name = "clouds", clouds.vs = "fullscreen.vert", clouds.fs = "cloud.frag", clouds.target = "hdr";
  clouds.cs = "cloud.comp";
  clouds.inputs = {{"scene", 0}, {"scene", 1}}, clouds.group = Group::Clouds;
  clouds.enabled = [](const FrameSetup& f) { return !temporal_on(f); };
  p.push_back(clouds);
  // render.temporal: the cloud layer at 1/16 of the pixels, resolved with the history, composited
  // over the background at every pixel. When nothing moved since the last frame only the pixels
  // marched in it change: the held frame keeps last frame's resolved layer and composed image in
  // place (render() does not swap the history then), and one pass marches its pixels, composes
  // them and stores them into both (a program of its own: llvmpipe would run the reprojection
  // whatever the uniforms say).
  Pass sparse;
  sparse.name = "clouds_sparse", sparse.vs = "fullscreen.vert", sparse.fs = "cloud_sparse.frag";
  sparse.cs = "cloud_sparse.comp";
  sparse.target = "cloud_quarter", sparse.inputs = {{"scene", 1}}, sparse.group = Group::Clouds;
  sparse.enabled = temporal, sparse.history_held = 0;
  Pass held = sparse;
  held.name = "clouds_sparse_held", held.fs = "cloud_sparse_held.frag", held.cs = "cloud_sparse_held.comp";
  held.cs_outputs = 2;  // the quarter target's (L, T) and distance, as the fragment stage writes them
  held.inputs = {{"scene", 1}, {"scene", 0}}, held.images = {{"cloud_layer", 0}, {"cloud_layer", 1}, {"hdr", 0}};
  held.history_held = 1;
  p.push_back(sparse);
  p.push_back(held);
  Pass resolve;
  resolve.name = "temporal_resolve", resolve.vs = "fullscreen.vert", resolve.fs = "temporal_resolve.frag";
  resolve.cs = "temporal_resolve.comp";
  resolve.target = "cloud_layer", resolve.group = Group::Clouds, resolve.enabled = temporal;
  resolve.inputs = {{"cloud_quarter", 0}, {"cloud_quarter", 1}, {"cloud_layer@prev", 0}, {"cloud_layer@prev", 1}};
  resolve.history_held = 0;
  p.push_back(resolve);
  Pass over;
  over.name = "temporal_compose", over.vs = "fullscreen.vert", over.fs = "temporal_compose.frag";
  over.cs = "temporal_compose.comp";
  over.target = "hdr", over.group = Group::Clouds, over.enabled = temporal;
  over.inputs = {{"cloud_layer", 0}, {"scene", 0}, {"scene", 1}, {"cloud_quarter", 2}, {"cloud_quarter", 3},
                {"cloud_quarter", 4}};
  over.history_held = 0;
  p.push_back(over);
  Pass bright;
  bright.name = "bloom_bright", bright.vs = "fullscreen.vert", bright.fs = "bloom_bright.frag";
  bright.cs = "bloom_bright.comp";
  bright.target = "bloom_a", bright.inputs = {{"hdr", 0}}, bright.enabled = bloom_on;
  p.push_back(bright);
  for (int axis = 0; axis < 2; ++axis) {
    Pass blur;
    blur.name = axis == 0 ? "bloom_blur_x" : "bloom_blur_y";
    blur.vs = "fullscreen.vert", blur.fs = "bloom_blur.frag", blur.cs = "bloom_blur.comp";
    blur.target = axis == 0 ? "bloom_b" : "bloom_a";
    blur.inputs = {{axis == 0 ? "bloom_a" : "bloom_b", 0}};
    blur.enabled = bloom_on;
    blur.uniforms = [axis](GLuint prog) { glProgramUniform2i(prog, 0, axis == 0 ? 1 : 0, axis == 0 ? 0 : 1); };
    p.push_back(blur);
  }
  Pass tonemap;
  tonemap.name = "tonemap", tonemap.vs = "fullscreen.vert", tonemap.fs = "tonemap.frag", tonemap.target = "final";
  tonemap.cs = "tonemap.comp";
  tonemap.inputs = {{"hdr", 0}, {"bloom_a", 0}};
  p.push_back(tonemap);
  return p;
}

// An occupancy grid (0 / non-0 per cell, x fastest) into its R8 3D texture of n cells, as 0 / 255:
// the shaders' occupancy_texel reads 1 where a cell may hold density.
void upload_mask(GLuint tex, glm::ivec3 n, const std::vector<uint8_t>& mask) {
  std::vector<uint8_t> texels(mask.size());
  for (size_t i = 0; i < texels.size(); ++i) texels[i] = mask[i] ? 255 : 0;
  glTextureSubImage3D(tex, 0, 0, 0, 0, n.x, n.y, n.z, GL_RED, GL_UNSIGNED_BYTE, texels.data());
}

// The ground mesh in units of the ground's half extent (ground.vert scales and bends it): a quad
// for box mode, then a CV_GROUND_GRID^2 grid for the curved Earth of layer mode. Uploaded once.
std::vector<float> ground_mesh(GLint& quad_first, GLsizei& quad_count, GLint& grid_first, GLsizei& grid_count) {
  std::vector<float> v = {-1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1};
  quad_first = 0, quad_count = 6;
  const int n = CV_GROUND_GRID;
  auto vertex = [&](int i, int j) { v.insert(v.end(), {float(-1.0 + 2.0 * i / n), float(-1.0 + 2.0 * j / n)}); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1);
      vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1);
    }
  grid_first = 6, grid_count = GLsizei(v.size() / 2) - 6;
  return v;
}

}  // namespace

namespace {

/// What a frame's temporal history was rendered with: a later frame reprojects it only when every
/// field matches (its time and frame index advance every frame by design and are left out).
struct HistoryKey {
  std::string settings;  ///< render.* and motion.* values (describe_settings)
  double sun_azimuth_deg = 0, sun_elevation_deg = 0;
  int width = 0, height = 0;
  bool operator==(const HistoryKey& o) const {
    return settings == o.settings && sun_azimuth_deg == o.sun_azimuth_deg &&
           sun_elevation_deg == o.sun_elevation_deg && width == o.width && height == o.height;
  }
  bool operator!=(const HistoryKey& o) const { return !(*this == o); }
};

HistoryKey history_key_of(const FrameSetup& f) {
  RenderSettings keyed = f.settings;
  keyed.frame = 0;
  keyed.time = 0;
  return {describe_settings(keyed), f.sun.azimuth_deg, f.sun.elevation_deg, f.width, f.height};
}

/// Stores `key` in `stored` and says whether it differs from what was there (a cache to rebuild).
bool changed(std::vector<double>& stored, std::vector<double> key) {
  const bool dirty = key != stored;
  stored = std::move(key);
  return dirty;
}

}  // namespace

struct GlRenderer::Impl {
  ShaderSource shaders;
  std::vector<Target> targets = make_targets();
  std::vector<Pass> passes = make_passes();
  GLuint tex_volume = 0, tex_occ = 0, tex_dist = 0, tex_mie = 0, tex_coverage = 0, tex_motion = 0, tex_curl = 0,
         tex_detail = 0;
  int detail_size = 0;  ///< edge of tex_detail's texels (render.detail_size)
  glm::ivec3 dist_dims{0};  // the distance field texture's cells (set_distance_field re-uploads into it)
  GLuint tex_moved_occ = 0;           // FrameSetup::moved_occupancy (R8), bound for occupied() while clouds move
  glm::ivec3 moved_occ_dims{0, 0, 0};  // its allocated size
  int volume_serial = 0;              // counts set_volume calls (part of the light volume's key)
  GLuint tex_image = 0, fbo_image = 0;  // present_image's texture and its framebuffer
  int image_w = 0, image_h = 0;
  std::vector<double> light_key;      // what the light volume was built from; empty = not built
  int light_builds = 0;
  std::vector<double> shadow_key;     // what the ground shadow map was built from; empty = not built
  int shadow_builds = 0;
  bool ground_reuse = true;           // a held temporal frame keeps last frame's ground (set_ground_reuse)
  int ground_draws = 0;
  std::vector<double> air_key;        // what the air LUT was built from; empty = not built
  int air_builds = 0;
  int atmo_generation = 0;            // counts the atmosphere LUTs' recomputes (part of the air LUT's key)
  GLuint tex_ms = 0;                  // render.ms_volume: the solved fluence and flux (RGBA32F, ms_volume_dims)
  std::vector<double> ms_key;         // what it was solved from; empty = not built
  int ms_builds = 0;
  MsDiffusionResult ms_last;          // the last solve (its fluence moved into tex_ms)
  GLuint ubo_cloud = 0, ubo_frame = 0, ubo_atmo = 0;
  GLuint buf_nano = 0, tex_nano = 0;  // render.volume=nanovdb: the grids and their buffer texture (else 32 bytes)
  int nvdb_on = 0, nvdb_detail = 0, nvdb_shared = 0, nvdb_table = 0, nvdb_ssbo = 0;
  GLuint tex_pages = 0;  // the leaf page table (cloudgen::NanoPages of the density and detail 1)
  glm::ivec3 nvdb_page_origin{0};
  bool nvdb_pages_ok = false;
  uint64_t pages_bytes = 0;
  glm::ivec3 nvdb_index_min{0};
  glm::uvec4 nvdb_grid{0u};
  // render.nanovdb_lookup=atlas: the grids' brick atlas (scene.h NanoAtlas), built on the first
  // frame that asks for it; bound at the dense volume's unit, its index at the page table's.
  PreparedVolume atlas_of;  // what build_nano_atlas and ensure_grids read of the volume (nano, dims, tiles, detail)
  GLuint tex_atlas = 0, tex_atlas_index = 0;
  int atlas_state = 0;  // 0 not built, 1 built, -1 refused (beyond kAtlasBudget: the page table instead)
  bool tree_atlas_noted = false;  // said once: tree skipping over grids beyond a storage buffer skips the atlas
  static constexpr uint64_t kAtlasBudget = uint64_t(1) << 30;
  bool ensure_atlas() {
    if (atlas_state != 0) return atlas_state > 0;
    GLint max3d = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
    const auto t0 = std::chrono::steady_clock::now();
    const NanoAtlas a = build_nano_atlas(atlas_of, max3d, kAtlasBudget);
    if (a.cells[0] == 0) {
      std::cerr << "cloudviewer: the NanoVDB brick atlas would exceed " << (kAtlasBudget >> 20) << " MiB or a "
                << max3d << "^3 texture; render.nanovdb_lookup=atlas falls back to the page table\n";
      atlas_state = -1;
      return false;
    }
    const int B = NanoAtlas::kBrick;
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_atlas);
    glTextureStorage3D(tex_atlas, 1, a.channels == 1 ? GL_R32F : GL_RGBA32F, a.layout[0] * B, a.layout[1] * B,
                       a.layout[2] * B);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage3D(tex_atlas, 0, 0, 0, 0, a.layout[0] * B, a.layout[1] * B, a.layout[2] * B,
                        a.channels == 1 ? GL_RED : GL_RGBA, GL_FLOAT, a.texels.data());
    glTextureParameteri(tex_atlas, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex_atlas, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTextureParameteri(tex_atlas, w, GL_CLAMP_TO_EDGE);
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_atlas_index);
    glTextureStorage3D(tex_atlas_index, 1, GL_RGBA16UI, a.cells[0], a.cells[1], a.cells[2]);
    glTextureSubImage3D(tex_atlas_index, 0, 0, 0, 0, a.cells[0], a.cells[1], a.cells[2], GL_RGBA_INTEGER,
                        GL_UNSIGNED_SHORT, a.index.data());
    glTextureParameteri(tex_atlas_index, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(tex_atlas_index, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    if (glGetError() != GL_NO_ERROR) {  // (out of GPU memory) the page table needs nothing more
      delete_atlas();
      atlas_state = -1;
      std::cerr << "cloudviewer: uploading the NanoVDB brick atlas (" << (a.bytes() >> 20)
                << " MiB) failed; render.nanovdb_lookup=atlas falls back to the page table\n";
      return false;
    }
    atlas_state = 1;
    const size_t cells = size_t(a.cells[0]) * a.cells[1] * a.cells[2];
    std::cerr << "cloudviewer: NanoVDB brick atlas: " << a.bricks << " bricks of 9^3 (" << std::lround(100.0 * a.bricks / cells)
              << "% of the " << cells << " leaf cells), " << std::lround(double(a.bytes()) / (1 << 20) * 10) / 10.0
              << " MiB on the GPU (the grids stay on the CPU), built in "
              << std::lround(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1000) << " ms\n";
    return true;
  }
  void delete_atlas() {
    if (tex_atlas) glDeleteTextures(1, &tex_atlas);
    if (tex_atlas_index) glDeleteTextures(1, &tex_atlas_index);
    tex_atlas = tex_atlas_index = 0;
    atlas_state = 0;
  }
  // The grids' buffer (and its buffer texture) and the leaf page table: placeholders (32 bytes,
  // one texel) until ensure_grids puts the volume's grids (atlas_of.nano) up. Both are immutable
  // storage, so an upload makes new objects.
  bool grids_up = false;
  void make_grid_objects() {
    if (tex_nano) glDeleteTextures(1, &tex_nano);
    if (buf_nano) glDeleteBuffers(1, &buf_nano);
    if (tex_pages) glDeleteTextures(1, &tex_pages);
    glCreateBuffers(1, &buf_nano);
    glCreateTextures(GL_TEXTURE_BUFFER, 1, &tex_nano);
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_pages);
    glTextureParameteri(tex_pages, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // integer: complete only unfiltered
    glTextureParameteri(tex_pages, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  void upload_grid_placeholders() {
    make_grid_objects();
    const uint32_t placeholder[8] = {};
    glNamedBufferStorage(buf_nano, sizeof placeholder, placeholder, 0);
    glTextureBuffer(tex_nano, GL_RGBA32UI, buf_nano);
    upload_empty_pages();
    grids_up = false;
    pages_bytes = 0;
  }
  // A page table of one empty entry (no grid has a table, or none is up yet).
  void upload_empty_pages() {
    const uint32_t none[2] = {0, 0};
    glTextureStorage3D(tex_pages, 1, GL_RG32UI, 1, 1, 1);
    glTextureSubImage3D(tex_pages, 0, 0, 0, 0, 1, 1, 1, GL_RG_INTEGER, GL_UNSIGNED_INT, none);
  }
  void ensure_grids() {
    if (grids_up || !atlas_of.nano) return;
    const cloudgen::NanoVolume& n = *atlas_of.nano;
    make_grid_objects();
    GLint max_texels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    glNamedBufferStorage(buf_nano, GLsizeiptr(n.bytes()), n.data(), 0);
    if (n.bytes() / 16 <= uint64_t(max_texels)) glTextureBuffer(tex_nano, GL_RGBA32UI, buf_nano);
    if (nvdb_pages_ok) {
      const cloudgen::NanoPages d = cloudgen::nano_pages(n, 0);
      const cloudgen::NanoPages g = nvdb_detail ? cloudgen::nano_pages(n, size_t(n.detail[0])) : d;
      if (d.origin != g.origin || d.dims != g.dims) throw GlError("NanoVDB page tables of different boxes");
      std::vector<uint32_t> rg(d.entries.size() * 2);
      for (size_t i = 0; i < d.entries.size(); ++i) rg[2 * i] = d.entries[i], rg[2 * i + 1] = g.entries[i];
      glTextureStorage3D(tex_pages, 1, GL_RG32UI, GLsizei(d.dims[0]), GLsizei(d.dims[1]), GLsizei(d.dims[2]));
      glTextureSubImage3D(tex_pages, 0, 0, 0, 0, GLsizei(d.dims[0]), GLsizei(d.dims[1]), GLsizei(d.dims[2]), GL_RG_INTEGER,
                          GL_UNSIGNED_INT, rg.data());
      nvdb_page_origin = glm::ivec3(d.origin[0], d.origin[1], d.origin[2]);
      pages_bytes = rg.size() * 4;
    } else {
      upload_empty_pages();
    }
    if (glGetError() != GL_NO_ERROR)
      throw GlError("uploading the NanoVDB grids (" + std::to_string(n.bytes() >> 20) + " MiB) failed (out of GPU memory?)");
    grids_up = true;
    std::cerr << "cloudviewer: NanoVDB grids" << (nvdb_pages_ok ? " and leaf page table" : "") << " on the GPU: "
              << std::lround(double(n.bytes() + pages_bytes) / (1 << 20) * 10) / 10.0 << " MiB\n";
  }
  bool atmo_valid = false;            // the LUT targets hold `atmo_done`'s tables
  AtmosphereSettings atmo_done;
  GLuint vao_empty = 0, vao_ground = 0, vbo_ground = 0;
  GLint quad_first = 0, grid_first = 0;
  GLsizei quad_count = 0, grid_count = 0;
  int w = 0, h = 0;
  std::vector<GLuint> queries;  // one timestamp before the passes and one after each
  bool have_volume = false;
  // Temporal upsampling: what the history in "cloud_layer@prev" was rendered with.
  bool history_valid = false;
  bool history_held = false;  // this frame: temporal, history valid, nothing moved (clouds_sparse_held
                              // runs instead of clouds_sparse, temporal_resolve and temporal_compose)
  HistoryKey history_key;        // settings, sun and size it was rendered with
  glm::dvec3 history_eye{0.0};
  glm::dmat4 history_view_proj{1.0};
  double history_time = 0;

  Target& target(const std::string& name) {
    for (Target& t : targets)
      if (t.name == name) return t;
    throw GlError("render pass refers to an undeclared target '" + name + "'");
  }
  // Every program linked so far, by the expanded text of its two stages: passes sharing a program
  // share one GL object, and a set of modes seen before (modes.glsl, nanovdb_storage.glsl) costs no
  // second compile. Programs that do not include a switch's file are the same for every value.
  std::map<std::string, GLuint> program_cache;
  std::string modes_text;  // modes.glsl's override; empty = the file (the modes read at run time)
  void delete_programs() {
    for (auto& c : program_cache) glDeleteProgram(c.second);
    program_cache.clear();
    for (Pass& p : passes) p.program = 0;
  }
  // What build_programs linked since render() last asked (GpuTimings::compile_ms, programs_linked).
  double compile_ms = 0;
  int programs_linked = 0;
  void build_programs() {
    // Link what the cache lacks; nothing changes unless all succeed.
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::string> keys;
    std::vector<std::pair<std::string, GLuint>> built;
    try {
      for (const Pass& p : passes) {
        std::vector<std::string> files;
        const bool cs = compute_on && !p.cs.empty();
        std::string key = cs ? "compute" + std::string(1, '\0') + shaders.expand(p.cs, files)
                             : shaders.expand(p.vs, files) + '\0' + shaders.expand(p.fs, files);
        bool have = program_cache.count(key) > 0;
        for (auto& b : built) have = have || b.first == key;
        if (!have) built.push_back({key, cs ? link_compute_program(shaders, p.cs) : link_program(shaders, p.vs, p.fs)});
        keys.push_back(std::move(key));
      }
    } catch (...) {
      for (auto& b : built) glDeleteProgram(b.second);
      throw;
    }
    for (auto& b : built) program_cache.emplace(std::move(b.first), b.second);
    for (size_t i = 0; i < passes.size(); ++i) {
      passes[i].program = program_cache.at(keys[i]);
      passes[i].compute = compute_on && !passes[i].cs.empty();
    }
    // (the link status query above waits for the driver, so this is the compile's wall time)
    if (!built.empty()) compile_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    programs_linked += int(built.size());
  }
  // render.compute: the passes that have a compute shader run it (use_modes builds per choice).
  bool compute_on = false;
  // render.compiled_modes and render.compute: the programs for this frame (built once per set of values).
  void use_modes(const FrameSetup& f) {
    std::string text = f.settings.compiled_modes ? compiled_modes_text(f.params) : std::string();
    const bool compute = f.settings.compute;
    if (text == modes_text && compute == compute_on) return;
    auto apply = [this](const std::string& t) {
      if (t.empty()) shaders.clear_override("modes.glsl");
      else shaders.set_override("modes.glsl", t);
    };
    const bool compute_before = compute_on;
    apply(text);
    compute_on = compute;
    try {
      build_programs();
    } catch (...) {  // (a file broken under --shader-dir) keep the programs and the modes they were built for
      apply(modes_text);
      compute_on = compute_before;
      throw;
    }
    modes_text = text;
  }
  // All targets, or (a viewport resize) only those the viewport sizes: the LUTs and the 3D
  // targets keep their contents (a window resize recomputes nothing).
  void delete_targets(bool viewport_only = false) {
    for (Target& t : targets)
      for (int c = 0; c < 2 && !(viewport_only && (t.volume_size || t.fixed_w > 0)); ++c) {
        if (t.fbo[c]) glDeleteFramebuffers(1, &t.fbo[c]);
        for (GLuint x : t.tex[c]) glDeleteTextures(1, &x);
        if (t.depth_tex[c]) glDeleteTextures(1, &t.depth_tex[c]);
        t.fbo[c] = t.depth_tex[c] = 0;
        t.tex[c].clear();
      }
    if (!viewport_only) forget_tables();
  }
  // The tables the frame computes once and keeps (the atmosphere and air LUTs, the light volume,
  // the shadow map, the diffusion inputs) are computed again on the next frame.
  void forget_tables() {
    atmo_valid = false;
    light_key.clear();
    shadow_key.clear();
    air_key.clear();
    ms_key.clear();
  }
  void resize(int width, int height) {
    if (width == w && height == h) return;
    delete_targets(true);
    w = width, h = height;
    for (Target& t : targets) {
      if (t.volume_size) continue;           // ensure_volume_target
      if (t.fixed_w > 0 && t.fbo[0]) continue;  // a LUT: kept
      int up = t.round_up ? t.divisor - 1 : 0;
      t.w = t.fixed_w > 0 ? t.fixed_w : std::max(1, (w + up) / t.divisor);
      t.h = t.fixed_h > 0 ? t.fixed_h : std::max(1, (h + up) / t.divisor);
      for (int c = 0; c < (t.history ? 2 : 1); ++c) {
        glCreateFramebuffers(1, &t.fbo[c]);
        std::vector<GLenum> draw;
        for (size_t i = 0; i < t.colors.size(); ++i) {
          t.tex[c].push_back(make_texture_2d(t.colors[i], t.w, t.h));
          if (t.linear_from >= 0 && int(i) >= t.linear_from) {
            glTextureParameteri(t.tex[c].back(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTextureParameteri(t.tex[c].back(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
          }
          glNamedFramebufferTexture(t.fbo[c], GLenum(GL_COLOR_ATTACHMENT0 + i), t.tex[c].back(), 0);
          draw.push_back(GLenum(GL_COLOR_ATTACHMENT0 + i));
        }
        if (t.depth) {
          t.depth_tex[c] = make_texture_2d(GL_DEPTH_COMPONENT32F, t.w, t.h);
          glNamedFramebufferTexture(t.fbo[c], GL_DEPTH_ATTACHMENT, t.depth_tex[c], 0);
        }
        glNamedFramebufferDrawBuffers(t.fbo[c], GLsizei(draw.size()), draw.data());
        check_fbo(t.fbo[c], t.name.c_str());
      }
    }
  }
  // A 3D target: (re)created when the frame asks for another size; true when it was.
  bool ensure_volume_target(Target& t, const FrameSetup& f) {
    glm::ivec3 n = glm::max(t.volume_size(f), glm::ivec3(1));
    if (t.fbo[0] && n == glm::ivec3(t.w, t.h, t.d)) return false;
    if (t.fbo[0]) glDeleteFramebuffers(1, &t.fbo[0]);
    for (GLuint x : t.tex[0]) glDeleteTextures(1, &x);
    t.tex[0].clear();
    t.w = n.x, t.h = n.y, t.d = n.z;
    glCreateFramebuffers(1, &t.fbo[0]);
    std::vector<GLenum> draw;
    for (size_t i = 0; i < t.colors.size(); ++i) {
      GLuint tex;
      glCreateTextures(GL_TEXTURE_3D, 1, &tex);
      glTextureStorage3D(tex, 1, t.colors[i], n.x, n.y, n.z);
      glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      t.tex[0].push_back(tex);
      glNamedFramebufferTextureLayer(t.fbo[0], GLenum(GL_COLOR_ATTACHMENT0 + i), tex, 0, 0);
      draw.push_back(GLenum(GL_COLOR_ATTACHMENT0 + i));
    }
    glNamedFramebufferDrawBuffers(t.fbo[0], GLsizei(draw.size()), draw.data());
    check_fbo(t.fbo[0], t.name.c_str());
    if (glGetError() != GL_NO_ERROR) throw GlError("creating the 3D target '" + t.name + "' failed (out of GPU memory?)");
    return true;
  }
  // The curl field (cloudgen/curl_distortion.glsl reads it with texelFetch and filters by hand, as
  // the CPU reference does), built and uploaded the first time a frame distorts the detail: it is
  // off by default, and building it costs a few milliseconds.
  // The Mie table (1D RGB float texture, fetched by index and interpolated by hand), uploaded for
  // the first Mie frame (computing it takes seconds) and again when a frame brings another table.
  uint64_t mie_uploaded = 0;
  // The coverage map whose texels are on the GPU (layer mode), held so that its address cannot
  // be reused by another map.
  std::shared_ptr<const std::vector<float>> coverage_uploaded;
  void ensure_mie_texture(const MiePhaseTable& mie) {
    if (tex_mie && mie.id == mie_uploaded) return;
    if (!tex_mie) {
      glCreateTextures(GL_TEXTURE_1D, 1, &tex_mie);
      glTextureStorage1D(tex_mie, 1, GL_RGB32F, CV_MIE_TABLE_SIZE);
      glTextureParameteri(tex_mie, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(tex_mie, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glTextureSubImage1D(tex_mie, 0, 0, GLsizei(mie.size()), GL_RGB, GL_FLOAT, mie.rgb.data());
    mie_uploaded = mie.id;
  }
  void ensure_curl_texture() {
    if (tex_curl) return;
    const std::vector<glm::vec4>& curl = cloudgen::curl_field_texels();
    const int n = cloudgen::kCurlFieldSize;
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_curl);
    glTextureStorage3D(tex_curl, 1, GL_RGBA32F, n, n, n);
    glTextureSubImage3D(tex_curl, 0, 0, 0, 0, n, n, n, GL_RGBA, GL_FLOAT, curl.data());
    glTextureParameteri(tex_curl, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(tex_curl, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  // render.detail's texture (detail_texture.h): R32F, repeating on every axis, trilinear; made again
  // when the size changes.
  void ensure_detail_texture(int n) {
    if (tex_detail && detail_size == n) return;
    if (tex_detail) glDeleteTextures(1, &tex_detail);
    const std::shared_ptr<const std::vector<float>> d = detail_texture(n);
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_detail);
    glTextureStorage3D(tex_detail, 1, GL_R32F, n, n, n);
    glTextureSubImage3D(tex_detail, 0, 0, 0, 0, n, n, n, GL_RED, GL_FLOAT, d->data());
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTextureParameteri(tex_detail, wrap, GL_REPEAT);
    glTextureParameteri(tex_detail, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex_detail, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    detail_size = n;
  }
  // What the light volume depends on, camera excluded (positions are camera-relative, the texels
  // are in the march box's own coordinates): the sun, the volume, the medium, the light march and,
  // while the clouds move, the march box and the motion at this time.
  std::vector<double> light_volume_key(const FrameSetup& f) const {
    const ref::CloudParams& p = f.params;
    std::vector<double> k = sun_medium_key(f);
    k.insert(k.end(), {p.light_mode, p.light_samples, p.light_step_m, p.light_growth, p.light_volume_dims.x,
                       p.light_volume_dims.y, p.light_volume_dims.z});
    std::vector<double> mk = motion_key(f);
    k.insert(k.end(), mk.begin(), mk.end());
    return k;
  }
  // The march box's size and the motion at this frame's time (its offset from the volume follows
  // from them), for the passes that march the moving density over the box.
  std::vector<double> motion_key(const FrameSetup& f) const {
    const ref::CloudParams& p = f.params;
    return {p.march_size_m.x, p.march_size_m.y, p.march_size_m.z, p.layer_on, p.motion_on,
            p.motion_on > 0.5 ? p.time_s : 0.0, p.wind_dir_x, p.wind_dir_z, p.wind_speed_mps, p.wind_shear,
            p.flow_speed_hz, p.flow_up_m, p.flow_forward_m};
  }
  // What every march toward the sun reads, camera excluded: the sun, the volume, the density
  // (medium, filter, curl distortion) and whether the distance field skips its samples.
  std::vector<double> sun_medium_key(const FrameSetup& f) const {
    const ref::CloudParams& p = f.params;
    return {double(volume_serial), p.sun_dir.x, p.sun_dir.y, p.sun_dir.z, p.volume_size_m.x, p.volume_size_m.y,
            p.volume_size_m.z, p.tiles_xz, p.has_detail, p.sigma_t_per_m, p.erosion, p.density_scale,
            p.exact_filter, p.df_light, p.curl_amplitude_m, p.curl_repeats.x, p.curl_repeats.y, p.curl_repeats.z,
            p.curl_shift, p.fine_detail_strength, p.fine_detail_size, p.fine_detail_repeats.x, p.fine_detail_repeats.y,
            p.fine_detail_repeats.z};
  }
  // The ground shadow map's key: the sun and the medium (not the light march's keys), its grid,
  // the march box and the ground in it, the shadow march and the motion at this time (all
  // independent of the camera: shadow_map_ground_m is the ground's height in the march box).
  std::vector<double> shadow_map_key(const FrameSetup& f) const {
    const ref::CloudParams& p = f.params;
    std::vector<double> k = sun_medium_key(f);
    k.insert(k.end(), {p.shadow_map_nx, p.shadow_map_nz, p.shadow_map_texel_m, p.shadow_map_min_x_m, p.shadow_map_min_z_m,
                       p.shadow_map_ground_m, p.shadow_samples, p.skip_distance, p.skip_tree, p.df_cell_m, p.df_margin_m,
                       p.moved_occ_cell_m});
    std::vector<double> mk = motion_key(f);
    k.insert(k.end(), mk.begin(), mk.end());
    return k;
  }
  // The diffusion volume's key: the light volume's, its grid, the albedo and the phase function.
  std::vector<double> ms_volume_key(const FrameSetup& f) const {
    const ref::CloudParams& p = f.params;
    std::vector<double> k = light_volume_key(f);
    k.insert(k.end(), {p.light_volume_on, p.ms_volume_dims.x, p.ms_volume_dims.y, p.ms_volume_dims.z, p.albedo,
                       p.phase_mode, p.hg_g, p.hg_g2, p.lobe_weight, p.draine_g_hg, p.draine_g_d, p.draine_alpha,
                       p.draine_w_d, double(p.phase_mode == CV_PHASE_MIE && f.mie ? f.mie->id : 0)});
    return k;
  }
  // After the ms_volume pass: its cells read back, the diffusion solved, the fluence uploaded.
  void solve_ms_volume(const FrameSetup& f) {
    const Target& t = target("ms_source");
    const size_t cells = size_t(t.w) * size_t(t.h) * size_t(t.d);
    std::vector<glm::vec2> px(cells);
    glGetTextureImage(t.tex[0][0], 0, GL_RG, GL_FLOAT, GLsizei(cells * sizeof(glm::vec2)), px.data());
    MsDiffusionGrid g = ms_diffusion_grid(f.params);  // its dims are the target's (ms_volume_dims)
    for (size_t i = 0; i < cells; ++i) g.sigma_t[i] = px[i].x, g.source[i] = px[i].y;
    const MsDiffusionOptions o = ms_diffusion_options(f.params, f.mie);
    ms_last = solve_ms_diffusion(g, o);
    const std::vector<glm::dvec4> texels = ms_volume_texels(ms_last, o.asymmetry);
    std::vector<glm::vec4> data(texels.begin(), texels.end());
    if (tex_ms) glDeleteTextures(1, &tex_ms);
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_ms);
    glTextureStorage3D(tex_ms, 1, GL_RGBA32F, t.w, t.h, t.d);
    glTextureSubImage3D(tex_ms, 0, 0, 0, 0, t.w, t.h, t.d, GL_RGBA, GL_FLOAT, data.data());
    glTextureParameteri(tex_ms, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex_ms, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(tex_ms, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex_ms, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex_ms, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    ms_last.fluence.clear();
    ms_last.flux.clear();
    ms_builds += 1;
  }
  // nanovdb_storage.glsl's switches: rebuilds the programs when they change.
  int storage = 0;  // 0 dense, 1 nanovdb from a storage buffer, 2 nanovdb from a buffer texture, 3 the brick atlas
  void use_storage(int st) {
    if (st == storage) return;
    shaders.set_override("nanovdb_storage.glsl", std::string("#define CV_NANOVDB ") + (st ? "1" : "0") +
                                                     "\n#define CV_NANOVDB_BUFFER_TEXTURE " + (st == 2 ? "1" : "0") +
                                                     "\n#define CV_NANOVDB_ATLAS " + (st == 3 ? "1" : "0") + "\n");
    storage = st;
    build_programs();
  }
  // The nanovdb lookups' plain uniforms (cloud_bindings.glsl); passes without them skip them.
  void set_volume_uniforms(GLuint program) const {
    // (A program reads some of them or none: the atlas programs u_nvdb_detail, unless compiled
    // without detail, and with render.skipping=tree u_nvdb_grid and u_nvdb_index_min. Inactive
    // ones have location -1, which glUniform ignores.)
    if (!nvdb_on) return;
    glUniform1i(glGetUniformLocation(program, "u_nvdb_detail"), nvdb_detail);
    glUniform1i(glGetUniformLocation(program, "u_nvdb_shared"), nvdb_shared);
    glUniform1i(glGetUniformLocation(program, "u_nvdb_table"), nvdb_table);
    glUniform3i(glGetUniformLocation(program, "u_nvdb_page_origin"), nvdb_page_origin.x, nvdb_page_origin.y,
                nvdb_page_origin.z);
    glUniform3i(glGetUniformLocation(program, "u_nvdb_index_min"), nvdb_index_min.x, nvdb_index_min.y, nvdb_index_min.z);
    glUniform4ui(glGetUniformLocation(program, "u_nvdb_grid"), nvdb_grid.x, nvdb_grid.y, nvdb_grid.z, nvdb_grid.w);
  }
  void run(Pass& p, const FrameSetup& f) {
    Target& t = target(p.target);
    for (size_t i = 0; i < p.clear.size(); ++i) glClearNamedFramebufferfv(t.fbo[0], GL_COLOR, GLint(i), p.clear[i].data());
    if (t.depth) {
      const float one = 1.0f;
      glClearNamedFramebufferfv(t.fbo[0], GL_DEPTH, 0, &one);
    }
    if (p.enabled && !p.enabled(f)) return;
    if (p.history_held >= 0 && (p.history_held == 1) != history_held) return;
    p.drew = true;
    if (t.volume_size) {  // one draw per layer of the 3D target (the layer in uniform location 0)
      glUseProgram(p.program);
      set_volume_uniforms(p.program);
      glViewport(0, 0, t.w, t.h);
      glBindVertexArray(vao_empty);
      if (p.blend_attachment >= 0) {
        glEnablei(GL_BLEND, GLuint(p.blend_attachment));
        glBlendEquationi(GLuint(p.blend_attachment), GL_FUNC_ADD);
        glBlendFunci(GLuint(p.blend_attachment), GL_ONE, GL_ONE);
      }
      for (int z = 0; z < t.d; ++z) {
        for (size_t i = 0; i < t.tex[0].size(); ++i)
          glNamedFramebufferTextureLayer(t.fbo[0], GLenum(GL_COLOR_ATTACHMENT0 + i), t.tex[0][i], 0, z);
        glBindFramebuffer(GL_FRAMEBUFFER, t.fbo[0]);
        glProgramUniform1i(p.program, 0, z);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
      if (p.blend_attachment >= 0) glDisablei(GL_BLEND, GLuint(p.blend_attachment));
      return;
    }
    for (size_t i = 0; i < p.inputs.size(); ++i) {
      const std::string& name = p.inputs[i].first;
      bool prev = name.size() > 5 && name.compare(name.size() - 5, 5, "@prev") == 0;
      Target& in = target(prev ? name.substr(0, name.size() - 5) : name);
      static const GLuint units[] = {CV_UNIT_PASS_INPUT0, CV_UNIT_PASS_INPUT1, CV_UNIT_PASS_INPUT2, CV_UNIT_PASS_INPUT3,
                                     CV_UNIT_PASS_INPUT4, CV_UNIT_PASS_INPUT5};
      if (i >= sizeof(units) / sizeof(units[0])) throw GlError("render pass '" + p.name + "' reads too many inputs");
      glBindTextureUnit(units[i], in.tex[prev ? 1 : 0][size_t(p.inputs[i].second)]);
    }
    glUseProgram(p.program);
    set_volume_uniforms(p.program);
    if (p.uniforms) p.uniforms(p.program);
    // What the pass stores with imageStore, in image-unit order: its own images, then for a
    // compute pass its target's attachments (which a fragment pass writes as its outputs).
    std::vector<std::pair<const Target*, size_t>> outs;
    for (const auto& im : p.images) outs.push_back({&target(im.first), size_t(im.second)});
    if (p.compute) {
      const size_t n = p.cs_outputs < 0 ? t.tex[0].size() : std::min(t.tex[0].size(), size_t(p.cs_outputs));
      for (size_t a = 0; a < n; ++a) outs.push_back({&t, a});
    }
    if (outs.size() > size_t(CV_IMAGE_PASS_OUTPUT4 + 1))
      throw GlError("render pass '" + p.name + "' stores into too many images");
    for (size_t i = 0; i < outs.size(); ++i)
      glBindImageTexture(GLuint(CV_IMAGE_PASS_OUTPUT0 + i), outs[i].first->tex[0][outs[i].second], 0, GL_FALSE, 0,
                         GL_WRITE_ONLY, outs[i].first->colors[outs[i].second]);
    if (p.compute) {
      glDispatchCompute(GLuint((t.w + CV_COMPUTE_GROUP - 1) / CV_COMPUTE_GROUP),
                        GLuint((t.h + CV_COMPUTE_GROUP - 1) / CV_COMPUTE_GROUP), 1);
      // Later passes and the next frame read the images as textures and framebuffer attachments,
      // read-backs copy them, and the next frame's stores must follow these.
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                      GL_TEXTURE_UPDATE_BARRIER_BIT | GL_PIXEL_BUFFER_BARRIER_BIT);
      return;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo[0]);
    glViewport(0, 0, t.w, t.h);
    if (p.mesh) {
      bool layer = f.params.layer_on > 0.5;
      glEnable(GL_DEPTH_TEST);
      glDepthFunc(GL_LESS);
      glBindVertexArray(vao_ground);
      glDrawArrays(GL_TRIANGLES, layer ? grid_first : quad_first, layer ? grid_count : quad_count);
      glDisable(GL_DEPTH_TEST);
    } else {
      glBindVertexArray(vao_empty);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      // The later passes (and the next frame) read what it stored through texture fetches, and
      // draw into or read back the same textures as framebuffer attachments.
      if (!outs.empty()) glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    }
  }
  const Pass& pass(const std::string& name) const {
    for (const Pass& p : passes)
      if (p.name == name) return p;
    throw GlError("no render pass '" + name + "'");
  }
  // Uploads the atmosphere block; true when the LUTs must be recomputed (a key changed, or the
  // targets were recreated).
  bool atmosphere_dirty(const AtmosphereSettings& a) {
    gpu::AtmosphereParams ap = to_gpu(make_atmosphere_params(a));
    glNamedBufferSubData(ubo_atmo, 0, sizeof(ap), &ap);
    glBindBufferBase(GL_UNIFORM_BUFFER, CV_BINDING_ATMOSPHERE, ubo_atmo);
    bool dirty = !atmo_valid || a != atmo_done;
    atmo_valid = true, atmo_done = a;
    return dirty;
  }
  // An atmosphere LUT pass, run when `dirty` (an atmosphere.* key changed, or the LUT targets were
  // recreated) or when it was skipped since (a pass the frame may disable, the 4D scattering LUT),
  // its output then bound to its units for the passes after it: each LUT pass reads the LUTs
  // before it, and none samples its own target. `needed`: false for a frame that reads no LUT
  // (the analytic sky), which then computes none.
  void run_lut(Pass& p, const FrameSetup& f, bool dirty, bool needed = true) {
    for (int u : p.lut_units) glBindTextureUnit(GLuint(u), 0);
    if (dirty) p.lut_valid = false;
    const bool on = needed && (!p.enabled || p.enabled(f));
    Target& t = target(p.target);
    if (on && t.volume_size && ensure_volume_target(t, f)) p.lut_valid = false;
    if (p.orders_loop) glBindTextureUnit(CV_UNIT_ORDERS_SUM, 0);
    bool ran = false;
    if (on && !p.lut_valid) {
      run(p, f);
      p.lut_valid = true;
      p.runs += 1;
      ran = true;
    }
    for (size_t i = 0; i < p.lut_units.size() && i < t.tex[0].size(); ++i)
      glBindTextureUnit(GLuint(p.lut_units[i]), p.lut_valid ? t.tex[0][i] : 0);
    if (p.orders_loop && on) {
      if (ran) run_orders(f);
      glBindTextureUnit(CV_UNIT_ORDERS_SUM, target("orders_delta").tex[0][1]);
    }
  }
  // The orders 2..N of atmosphere.density_orders after the orders table's single parts: per order,
  // the density (reading the last order's light and the ground irradiance of the order before
  // it), the ground irradiance of the last order, then the order's light along each texel's ray,
  // added into the sum. A pass never samples the texture it writes.
  Pass& pass_named(const std::string& name) { return const_cast<Pass&>(pass(name)); }
  void run_orders(const FrameSetup& f) {
    Target& density = target("orders_density");
    Target& delta = target("orders_delta");
    Target& irr = target("orders_irradiance");
    ensure_volume_target(density, f);
    ensure_volume_target(delta, f);
    const float zero[4] = {0.f, 0.f, 0.f, 0.f};
    glClearTexImage(delta.tex[0][0], 0, GL_RGBA, GL_FLOAT, zero);
    glClearTexImage(delta.tex[0][1], 0, GL_RGBA, GL_FLOAT, zero);
    glClearTexImage(irr.tex[0][0], 0, GL_RGBA, GL_FLOAT, zero);
    Pass& pd = pass_named("atmosphere_orders_density");
    Pass& pi = pass_named("atmosphere_orders_irradiance");
    Pass& pm = pass_named("atmosphere_orders_multiple");
    for (int order = 2; order <= f.settings.atmosphere.scattering_orders; ++order) {
      glBindTextureUnit(CV_UNIT_ORDERS_DENSITY, 0);
      glBindTextureUnit(CV_UNIT_ORDERS_DENSITY_M, 0);
      glBindTextureUnit(CV_UNIT_ORDERS_DELTA, delta.tex[0][0]);
      glBindTextureUnit(CV_UNIT_ORDERS_IRRADIANCE, irr.tex[0][0]);
      glProgramUniform1i(pd.program, 1, order);
      run(pd, f);
      glBindTextureUnit(CV_UNIT_ORDERS_IRRADIANCE, 0);
      glProgramUniform1i(pi.program, 1, order - 1);
      run(pi, f);
      glBindTextureUnit(CV_UNIT_ORDERS_DELTA, 0);
      glBindTextureUnit(CV_UNIT_ORDERS_DENSITY, density.tex[0][0]);
      glBindTextureUnit(CV_UNIT_ORDERS_DENSITY_M, density.tex[0][1]);
      run(pm, f);
    }
    glBindTextureUnit(CV_UNIT_ORDERS_DENSITY, 0);
    glBindTextureUnit(CV_UNIT_ORDERS_DENSITY_M, 0);
  }
  // After every frame: this frame's copy becomes "NAME@prev". A held temporal frame swaps back
  // first (render()), so that it draws into last frame's copy in place.
  // The steps of a frame (GlRenderer::render).
  /// Which caches this frame rebuilds (each pass that builds one runs only then).
  struct Rebuilds {
    bool atmosphere = false, air = false, light = false, shadow = false, ms = false;
    bool any() const { return atmosphere || air || light || shadow || ms; }
  };
  /// The volume's storage for this frame (NanoVDB grids, page table or brick atlas); true: the atlas.
  bool choose_storage(const FrameSetup& f);
  /// The frame block, with the temporal history's state (and the history's key updated).
  FrameBlock frame_block(const FrameSetup& f);
  void upload_motion_table(const FrameSetup& f, bool history_usable);
  /// The march box's occupancy for moving clouds; false when the frame has none.
  bool upload_moved_occupancy(const FrameSetup& f);
  void bind_inputs(const FrameSetup& f, bool atlas, bool moved_occ);
  Rebuilds find_rebuilds(const FrameSetup& f);
  void run_passes(const FrameSetup& f, const Rebuilds& r, bool ground_kept);
  void read_timings(GpuTimings& timings, double compile_ms, int programs_linked);

  void swap_history() {
    for (Target& t : targets)
      if (t.history) {
        std::swap(t.fbo[0], t.fbo[1]);
        std::swap(t.tex[0], t.tex[1]);
        std::swap(t.depth_tex[0], t.depth_tex[1]);
      }
  }
};

GlRenderer::GlRenderer(ShaderSource shaders) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.shaders = std::move(shaders);
  m.build_programs();
  glCreateBuffers(1, &m.ubo_cloud);
  glNamedBufferStorage(m.ubo_cloud, sizeof(gpu::CloudParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateBuffers(1, &m.ubo_frame);
  glNamedBufferStorage(m.ubo_frame, sizeof(FrameBlock), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateBuffers(1, &m.ubo_atmo);
  glNamedBufferStorage(m.ubo_atmo, sizeof(gpu::AtmosphereParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateVertexArrays(1, &m.vao_empty);
  glCreateVertexArrays(1, &m.vao_ground);
  glCreateBuffers(1, &m.vbo_ground);
  std::vector<float> mesh = ground_mesh(m.quad_first, m.quad_count, m.grid_first, m.grid_count);
  glNamedBufferStorage(m.vbo_ground, GLsizeiptr(mesh.size() * sizeof(float)), mesh.data(), 0);
  glVertexArrayVertexBuffer(m.vao_ground, 0, m.vbo_ground, 0, sizeof(float) * 2);
  glEnableVertexArrayAttrib(m.vao_ground, 0);
  glVertexArrayAttribFormat(m.vao_ground, 0, 2, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(m.vao_ground, 0, 0);
  m.queries.resize(m.passes.size() + 1);
  glCreateQueries(GL_TIMESTAMP, GLsizei(m.queries.size()), m.queries.data());
  const int n = CV_COVERAGE_MAP_SIZE;  // its texels come with the first layer frame (FrameSetup::coverage)
  glCreateTextures(GL_TEXTURE_2D, 1, &m.tex_coverage);
  glTextureStorage2D(m.tex_coverage, 1, GL_RG32F, n, n);
  glTextureParameteri(m.tex_coverage, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_coverage, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glCreateTextures(GL_TEXTURE_2D, 1, &m.tex_motion);  // medium.glsl's motion table, 2 rows
  glTextureStorage2D(m.tex_motion, 1, GL_RGBA32F, CV_MOTION_LUT_SIZE, 2);
  glTextureParameteri(m.tex_motion, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_motion, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

GlRenderer::~GlRenderer() {
  Impl& m = *impl_;
  m.delete_programs();
  m.delete_targets();
  m.delete_atlas();
  GLuint texs[] = {m.tex_volume, m.tex_occ, m.tex_dist, m.tex_mie, m.tex_coverage, m.tex_motion, m.tex_curl, m.tex_detail, m.tex_ms, m.tex_moved_occ};
  for (GLuint t : texs)
    if (t) glDeleteTextures(1, &t);
  if (m.fbo_image) glDeleteFramebuffers(1, &m.fbo_image);
  if (m.tex_image) glDeleteTextures(1, &m.tex_image);
  if (m.tex_nano) glDeleteTextures(1, &m.tex_nano);
  if (m.buf_nano) glDeleteBuffers(1, &m.buf_nano);
  if (m.tex_pages) glDeleteTextures(1, &m.tex_pages);
  glDeleteBuffers(1, &m.ubo_cloud);
  glDeleteBuffers(1, &m.ubo_frame);
  glDeleteBuffers(1, &m.ubo_atmo);
  glDeleteBuffers(1, &m.vbo_ground);
  glDeleteVertexArrays(1, &m.vao_empty);
  glDeleteVertexArrays(1, &m.vao_ground);
  glDeleteQueries(GLsizei(m.queries.size()), m.queries.data());
}

void GlRenderer::reload_shaders() {
  // The files may have changed: compile everything again, keeping the old programs if that fails.
  Impl& m = *impl_;
  std::map<std::string, GLuint> old;
  std::swap(old, m.program_cache);
  std::vector<GLuint> in_use;
  for (const Pass& p : m.passes) in_use.push_back(p.program);
  try {
    m.build_programs();
  } catch (...) {
    std::swap(old, m.program_cache);
    for (size_t i = 0; i < m.passes.size(); ++i) m.passes[i].program = in_use[i];
    throw;
  }
  for (auto& c : old) glDeleteProgram(c.second);
  // What the old programs computed (the cached tables, the temporal history) is computed again by
  // the new ones on the next frame.
  m.forget_tables();
  m.history_valid = false;
}

std::string GlRenderer::renderer_string() const {
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(r ? r : "?") + " / " + (v ? v : "?");
}

void GlRenderer::set_volume(const PreparedVolume& vol) {
  Impl& m = *impl_;
  if (m.tex_volume) glDeleteTextures(1, &m.tex_volume);
  if (m.tex_occ) glDeleteTextures(1, &m.tex_occ);
  if (m.tex_dist) glDeleteTextures(1, &m.tex_dist);
  m.tex_dist = 0;
  m.tex_volume = m.tex_occ = 0;  // (the grids' objects: upload_grid_placeholders replaces them below)
  glCreateTextures(GL_TEXTURE_3D, 1, &m.tex_volume);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  m.delete_atlas();
  m.atlas_of = PreparedVolume{};
  m.atlas_of.nano = vol.nano;
  m.atlas_of.dims = vol.dims;
  m.atlas_of.tiles = vol.tiles;
  m.atlas_of.has_detail = vol.has_detail;
  if (vol.nano) {
    // The grids as they are in memory (NanoVDB is position-independent: offsets are relative);
    // the dense texture becomes one texel the lookups never read.
    GLint max_texels = 0;
    GLint64 max_block = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    m.nvdb_ssbo = GLint64(vol.nano->bytes()) <= max_block ? 1 : 0;
    m.use_storage(m.nvdb_ssbo ? 1 : 2);
    if (!m.nvdb_ssbo && vol.nano->bytes() / 16 > uint64_t(max_texels))
      throw GlError("the NanoVDB grids need " + std::to_string(vol.nano->bytes() >> 20) +
                    " MiB, more than this GL's buffer textures hold (GL_MAX_TEXTURE_BUFFER_SIZE " +
                    std::to_string(max_texels) + " RGBA32UI texels)");
    // The grids and the page table go up when a frame first reads them (render.nanovdb_lookup=
    // table or accessor, or an atlas refused): the atlas, the default, needs neither, and on
    // cumulus-field 2048 the grids alone are 637 MiB. Until then a placeholder stands in.
    m.upload_grid_placeholders();
    m.nvdb_on = 1;
    m.nvdb_detail = vol.has_detail ? 1 : 0;
    m.nvdb_shared = vol.has_detail && vol.nano->detail_shared_layout ? 1 : 0;
    m.nvdb_index_min = glm::ivec3(vol.nano->index_min[0], vol.nano->index_min[1], vol.nano->index_min[2]);
    for (int g = 0; g < 4; ++g) {
      const int index = g == 0 ? 0 : std::max(vol.nano->detail[size_t(g - 1)], 0);
      m.nvdb_grid[g] = GLuint(vol.nano->grids[size_t(index)].offset);
    }
    // The page table when every grid the shaders read has one (the detail grids through the
    // first one's layout); otherwise the lookups walk the tree with PNanoVDB's accessor.
    m.nvdb_pages_ok = !vol.has_detail || m.nvdb_shared;
    const float zero[4] = {0, 0, 0, 0};
    glTextureStorage3D(m.tex_volume, 1, GL_RGBA32F, 1, 1, 1);
    glTextureSubImage3D(m.tex_volume, 0, 0, 0, 0, 1, 1, 1, GL_RGBA, GL_FLOAT, zero);
  } else {
    m.upload_grid_placeholders();
    m.nvdb_on = 0;
    m.nvdb_ssbo = 0;
    m.use_storage(0);
    m.nvdb_pages_ok = false;
    GLint max3d = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
    for (int i = 0; i < 3; ++i)
      if (vol.dims[i] > max3d)
        throw InputError("volume dimension " + std::to_string(vol.dims[i]) + " exceeds GL_MAX_3D_TEXTURE_SIZE " +
                         std::to_string(max3d) + " (render.volume=nanovdb has no such limit)");
    glTextureStorage3D(m.tex_volume, 1, GL_RGBA32F, vol.dims[0], vol.dims[1], vol.dims[2]);
    glTextureSubImage3D(m.tex_volume, 0, 0, 0, 0, vol.dims[0], vol.dims[1], vol.dims[2], GL_RGBA, GL_FLOAT, vol.rgba.data());
  }
  glTextureParameteri(m.tex_volume, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  GLint wrap_xz = vol.tiles ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_S, wrap_xz);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(m.tex_volume, GL_TEXTURE_WRAP_R, wrap_xz);
  glCreateTextures(GL_TEXTURE_3D, 1, &m.tex_occ);
  glTextureStorage3D(m.tex_occ, 1, GL_R8, vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  upload_mask(m.tex_occ, glm::ivec3(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]), vol.occ);
  glTextureParameteri(m.tex_occ, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_occ, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  // The distance field (integer cells, texelFetch only).
  glCreateTextures(GL_TEXTURE_3D, 1, &m.tex_dist);
  glTextureStorage3D(m.tex_dist, 1, GL_R8UI, vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  glTextureParameteri(m.tex_dist, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(m.tex_dist, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  m.dist_dims = glm::ivec3(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  set_distance_field(vol);
  m.volume_serial += 1;
  m.light_key.clear();
  m.shadow_key.clear();
  m.ms_key.clear();
  m.have_volume = true;
  m.history_valid = false;
  if (glGetError() != GL_NO_ERROR) throw GlError("uploading the volume textures failed (out of GPU memory?)");
}

void GlRenderer::set_distance_field(const PreparedVolume& vol) {
  Impl& m = *impl_;
  const glm::ivec3 n(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2]);
  if (!m.tex_dist || n != m.dist_dims) throw GlError("set_distance_field: not the grid set_volume uploaded");
  std::vector<uint8_t> dist = vol.dist;
  dist.resize(vol.occ.size(), 1);  // a volume prepared without the field: the thesis's one cell
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage3D(m.tex_dist, 0, 0, 0, 0, n.x, n.y, n.z, GL_RED_INTEGER, GL_UNSIGNED_BYTE, dist.data());
  m.light_key.clear();  // the light volume marches only the texels this field leaves readable
}


// The steps of GlRenderer::render, in order. Each reads the frame and the renderer's state.

bool GlRenderer::Impl::choose_storage(const FrameSetup& f) {
  // The nanovdb lookups' storage (nanovdb_storage.glsl) before the modes, so a change links once more.
  // Tree skipping (render.skipping=tree) walks the grids whatever the lookup: they go up too. The
  // atlas programs read them from a storage buffer; grids beyond one (128 MiB on llvmpipe) take
  // the page table's buffer texture instead.
  const bool tree = nvdb_on && f.params.skip_tree > 0.5;
  const bool atlas_wanted = nvdb_on && f.settings.nanovdb_lookup == NanoLookup::Atlas;
  if (atlas_wanted && tree && !nvdb_ssbo && !tree_atlas_noted) {
    std::cerr << "cloudviewer: render.skipping=tree walks grids larger than a storage buffer here: the frames read them "
                 "through the page table, not the brick atlas\n";
    tree_atlas_noted = true;
  }
  const bool atlas = atlas_wanted && (!tree || nvdb_ssbo) && ensure_atlas();
  if (nvdb_on && (!atlas || tree)) ensure_grids();
  use_storage(!nvdb_on ? 0 : atlas ? 3 : nvdb_ssbo ? 1 : 2);
  return atlas;
}

FrameBlock GlRenderer::Impl::frame_block(const FrameSetup& f) {
  const Target& bloom = target("bloom_a");
  FrameBlock fb;
  fb.inv_view_proj = glm::mat4(f.inv_view_proj);
  fb.view_proj = glm::mat4(f.view_proj);
  fb.viewport = glm::vec4(w, h, bloom.w, bloom.h);
  fb.post = glm::vec4(float(f.settings.exposure), float(int(f.settings.tonemap)), float(f.settings.bloom),
                      float(f.settings.bloom_threshold));
  // Temporal: the history is usable when it was rendered with the same settings, sun and size; it
  // maps pixel to pixel when the camera and the clouds have not moved since.
  const bool temporal = temporal_on(f);
  const HistoryKey key = history_key_of(f);
  const bool valid = temporal && history_valid && key == history_key;
  const bool clouds_still = f.params.motion_on < 0.5 ? history_time == f.settings.time || f.settings.time == 0
                                                     : history_time == f.settings.time;
  const bool still = valid && f.camera.eye == history_eye && f.view_proj == history_view_proj && clouds_still;
  glm::ivec2 offset = reference_cross_matrix_offset(f.settings.frame);
  // Last frame's clip from this frame's camera-relative position p: world = p + eye.
  glm::dmat4 prev = history_view_proj * glm::translate(glm::dmat4(1.0), f.camera.eye - history_eye);
  fb.prev_view_proj = glm::mat4(valid ? prev : f.view_proj);
  fb.temporal = glm::vec4(valid ? 1.f : 0.f, still ? 1.f : 0.f, float(offset.x), float(offset.y));
  history_held = still;
  if (f.params.motion_on > 0.5) upload_motion_table(f, valid);
  history_valid = temporal;
  history_key = key;
  history_eye = f.camera.eye;
  history_view_proj = f.view_proj;
  history_time = f.settings.time;
  return fb;
}

void GlRenderer::Impl::upload_motion_table(const FrameSetup& f, bool history_usable) {
  // This frame's D(h), and the last frame's for the reprojection.
  std::vector<glm::dvec3> rows = f.motion_table;
  if (history_usable) {
    std::vector<glm::dvec3> prev_row = motion_table_row(f.settings, history_time);
    std::copy(prev_row.begin(), prev_row.end(), rows.begin() + CV_MOTION_LUT_SIZE);
  }
  std::vector<glm::vec4> texels(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) texels[i] = glm::vec4(glm::vec3(rows[i]), 0.f);
  glTextureSubImage2D(tex_motion, 0, 0, 0, CV_MOTION_LUT_SIZE, 2, GL_RGBA, GL_FLOAT, texels.data());
}

bool GlRenderer::Impl::upload_moved_occupancy(const FrameSetup& f) {
  if (f.moved_occupancy.empty()) return false;  // the march box's occupancy at this time (medium.glsl occupied)
  const glm::ivec3 n(f.params.moved_occ_dims);
  if (n != moved_occ_dims) {
    if (tex_moved_occ) glDeleteTextures(1, &tex_moved_occ);
    glCreateTextures(GL_TEXTURE_3D, 1, &tex_moved_occ);
    glTextureStorage3D(tex_moved_occ, 1, GL_R8, n.x, n.y, n.z);
    glTextureParameteri(tex_moved_occ, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(tex_moved_occ, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    moved_occ_dims = n;
  }
  upload_mask(tex_moved_occ, n, f.moved_occupancy);
  return true;
}

void GlRenderer::Impl::bind_inputs(const FrameSetup& f, bool atlas, bool moved_occ) {
  glBindBufferBase(GL_UNIFORM_BUFFER, CV_BINDING_CLOUD, ubo_cloud);
  glBindBufferBase(GL_UNIFORM_BUFFER, CV_BINDING_FRAME, ubo_frame);
  glBindBufferBase(GL_UNIFORM_BUFFER, CV_BINDING_ATMOSPHERE, ubo_atmo);
  glBindTextureUnit(CV_UNIT_VOLUME, atlas ? tex_atlas : tex_volume);
  glBindTextureUnit(CV_UNIT_OCCUPANCY, moved_occ ? tex_moved_occ : tex_occ);
  glBindTextureUnit(CV_UNIT_DISTANCE, tex_dist);
  glBindTextureUnit(CV_UNIT_NANOVDB_GRIDS, tex_nano);
  // Beyond a storage block the shaders read the buffer texture; the storage binding then covers
  // only the first 32 bytes (a binding larger than GL_MAX_SHADER_STORAGE_BLOCK_SIZE is an error).
  if (nvdb_ssbo) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_BINDING_NANOVDB, buf_nano);
  else glBindBufferRange(GL_SHADER_STORAGE_BUFFER, CV_BINDING_NANOVDB, buf_nano, 0, 32);
  glBindTextureUnit(CV_UNIT_NANOVDB_PAGES, atlas ? tex_atlas_index : tex_pages);
  nvdb_table = nvdb_pages_ok && f.settings.nanovdb_lookup == NanoLookup::Table ? 1 : 0;
  if (int(f.params.phase_mode) == CV_PHASE_MIE) ensure_mie_texture(f.mie ? *f.mie : *computed_mie_table());
  glBindTextureUnit(CV_UNIT_MIE, tex_mie);
  if (f.coverage && f.coverage != coverage_uploaded) {
    const int n = CV_COVERAGE_MAP_SIZE;
    glTextureSubImage2D(tex_coverage, 0, 0, 0, n, n, GL_RG, GL_FLOAT, f.coverage->data());
    coverage_uploaded = f.coverage;
  }
  glBindTextureUnit(CV_UNIT_COVERAGE, tex_coverage);
  glBindTextureUnit(CV_UNIT_MOTION, tex_motion);
  if (f.params.curl_amplitude_m > 0) ensure_curl_texture();
  glBindTextureUnit(CV_UNIT_CURL, tex_curl);
  if (f.params.fine_detail_strength > 0) ensure_detail_texture(int(f.params.fine_detail_size));
  glBindTextureUnit(CV_UNIT_DETAIL, tex_detail);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_FRAMEBUFFER_SRGB);
}

GlRenderer::Impl::Rebuilds GlRenderer::Impl::find_rebuilds(const FrameSetup& f) {
  Rebuilds r;
  // The analytic sky reads no LUT: skip the precompute (and keep the LUTs' state for later frames).
  r.atmosphere = f.settings.sky == SkyMode::Precomputed && atmosphere_dirty(f.settings.atmosphere);
  if (r.atmosphere) atmo_generation += 1;
  // The air LUT: rebuilt when the sun, the camera's altitude, its source or the atmosphere changes.
  if (f.params.air_lut > 0.5) {
    if (ensure_volume_target(target("air"), f)) air_key.clear();
    r.air = changed(air_key, {f.params.sun_dir.x, f.params.sun_dir.y, f.params.sun_dir.z, f.params.sky_altitude_m,
                              f.params.sky_lut, double(atmo_generation)});
  }
  // Never sample the air LUT while its pass writes it.
  {
    const Target& air = target("air");
    const bool bound = f.params.air_lut > 0.5 && !r.air && air.tex[0].size() == 2;
    glBindTextureUnit(CV_UNIT_AIR, bound ? air.tex[0][0] : 0);
    glBindTextureUnit(CV_UNIT_AIR_MIE, bound ? air.tex[0][1] : 0);
  }
  // The light volume: rebuilt when its key changes (not when only the camera moves).
  Target& light = target("light_volume");
  if (f.params.light_volume_on > 0.5) {
    if (ensure_volume_target(light, f)) light_key.clear();
    r.light = changed(light_key, light_volume_key(f));
    // Wrapped like the volume (the key holds tiles_xz).
    GLint wrap_xz = f.params.tiles_xz > 0.5 ? GL_REPEAT : GL_CLAMP_TO_EDGE;
    glTextureParameteri(light.tex[0][0], GL_TEXTURE_WRAP_S, wrap_xz);
    glTextureParameteri(light.tex[0][0], GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(light.tex[0][0], GL_TEXTURE_WRAP_R, wrap_xz);
  }
  // Never sample the light volume while its pass writes it.
  glBindTextureUnit(CV_UNIT_LIGHT_VOLUME, r.light || light.tex[0].empty() ? 0 : light.tex[0][0]);
  // The ground shadow map: rebuilt when its key changes. Its target always exists (one texel when
  // off), since the ground pass binds it.
  if (ensure_volume_target(target("shadow_map"), f)) shadow_key.clear();
  if (f.params.shadow_map_on > 0.5) r.shadow = changed(shadow_key, shadow_map_key(f));
  // The diffusion volume: solved again when its key changes.
  if (f.params.ms_volume_on > 0.5) {
    if (ensure_volume_target(target("ms_source"), f)) ms_key.clear();
    r.ms = changed(ms_key, ms_volume_key(f));
  }
  glBindTextureUnit(CV_UNIT_MS_VOLUME, r.ms ? 0 : tex_ms);
  return r;
}

void GlRenderer::Impl::run_passes(const FrameSetup& f, const Rebuilds& r, bool ground_kept) {
  glQueryCounter(queries[0], GL_TIMESTAMP);
  for (Pass& p : passes) p.drew = false;
  for (size_t i = 0; i < passes.size(); ++i) {
    Pass& p = passes[i];
    if (p.driven) {
      // run by the orders loop inside its parent pass
    } else if (p.precompute) {
      run_lut(p, f, r.atmosphere, f.settings.sky == SkyMode::Precomputed);
    } else if (p.light_volume) {
      if (r.light) {
        run(p, f);
        light_builds += 1;
        glBindTextureUnit(CV_UNIT_LIGHT_VOLUME, target("light_volume").tex[0][0]);
      }
    } else if (p.shadow_map) {
      if (r.shadow) {
        run(p, f);
        shadow_builds += 1;
      }
    } else if (p.air_lut) {
      if (r.air) {
        run(p, f);
        air_builds += 1;
        const Target& air = target("air");
        glBindTextureUnit(CV_UNIT_AIR, air.tex[0][0]);
        glBindTextureUnit(CV_UNIT_AIR_MIE, air.tex[0][1]);
      }
    } else if (p.ms_volume) {
      if (r.ms) {  // its timing includes the read-back, the CPU solve and the upload
        run(p, f);
        solve_ms_volume(f);
        glBindTextureUnit(CV_UNIT_MS_VOLUME, tex_ms);
      }
    } else if (p.mesh && ground_kept) {
      // last frame's ground is still in "scene"
    } else {
      run(p, f);
      if (p.mesh && p.drew) ground_draws += 1;
    }
    glQueryCounter(queries[i + 1], GL_TIMESTAMP);
  }
}

void GlRenderer::Impl::read_timings(GpuTimings& timings, double compile, int linked) {
  std::vector<GLuint64> t(queries.size());
  for (size_t i = 0; i < t.size(); ++i) glGetQueryObjectui64v(queries[i], GL_QUERY_RESULT, &t[i]);
  timings = GpuTimings{};
  for (size_t i = 0; i < passes.size(); ++i) {
    double ms = double(t[i + 1] - t[i]) * 1e-6;
    if (passes[i].drew) timings.passes.push_back({passes[i].name + (passes[i].compute ? " (compute)" : ""), ms});
    Group g = passes[i].group;
    (g == Group::Atmosphere ? timings.atmosphere_ms : g == Group::Light ? timings.light_volume_ms
     : g == Group::Shadow ? timings.shadow_map_ms : g == Group::Ground ? timings.ground_ms
     : g == Group::Clouds ? timings.cloud_ms : timings.post_ms) += ms;
  }
  timings.total_ms = double(t.back() - t.front()) * 1e-6;
  timings.compile_ms = compile;
  timings.programs_linked = linked;
}

void GlRenderer::render(const FrameSetup& f, GpuTimings* timings) {
  Impl& m = *impl_;
  if (!m.have_volume) throw GlError("GlRenderer::render before set_volume");
  m.resize(f.width, f.height);
  const bool atlas = m.choose_storage(f);
  m.use_modes(f);  // and render.compute's programs
  const double compile_ms = m.compile_ms;
  const int programs_linked = m.programs_linked;
  m.compile_ms = 0, m.programs_linked = 0;
  gpu::CloudParams cp = to_gpu(f.params);
  glNamedBufferSubData(m.ubo_cloud, 0, sizeof(cp), &cp);
  FrameBlock fb = m.frame_block(f);
  const bool still = m.history_held;
  const bool moved_occ = m.upload_moved_occupancy(f);
  glNamedBufferSubData(m.ubo_frame, 0, sizeof(fb), &fb);
  m.bind_inputs(f, atlas, moved_occ);
  const Impl::Rebuilds r = m.find_rebuilds(f);

  // A held frame changes only the pixels it marches: last frame's resolved layer and composed
  // image stay where they are (the composed image in "hdr", which only the cloud passes write).
  if (still) m.swap_history();
  // Nor does it change the ground: "scene", which only the ground pass writes, holds last frame's,
  // drawn with the same settings, sun, size, camera, time and volume (what `still` compares),
  // unless a table the ground reads (the shadow map, the sky's LUTs, the air) is rebuilt now.
  const bool ground_kept = still && m.ground_reuse && !r.any();
  m.run_passes(f, r, ground_kept);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  m.swap_history();
  GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw GlError("OpenGL error 0x" + std::to_string(err) + " while rendering");
  if (timings) m.read_timings(*timings, compile_ms, programs_linked);
}

namespace {
// std140 layout as the driver sees it in the cloud program (tests compare it with the C++ structs).
int block_size(GLuint program, const char* block) {
  GLuint index = glGetUniformBlockIndex(program, block);
  GLint size = 0;
  glGetActiveUniformBlockiv(program, index, GL_UNIFORM_BLOCK_DATA_SIZE, &size);
  return size;
}
int member_offset(GLuint program, const std::string& name) {
  GLuint index = glGetProgramResourceIndex(program, GL_UNIFORM, name.c_str());
  if (index == GL_INVALID_INDEX) return -1;
  const GLenum prop = GL_OFFSET;
  GLint offset = -1;
  glGetProgramResourceiv(program, GL_UNIFORM, index, 1, &prop, 1, nullptr, &offset);
  return offset;
}
}  // namespace

int GlRenderer::cloud_block_size() const { return block_size(impl_->pass("clouds").program, "CloudBlock"); }
int GlRenderer::cloud_block_offset(const std::string& member) const {
  return member_offset(impl_->pass("clouds").program, "u_cloud." + member);
}
int GlRenderer::atmosphere_block_size() const { return block_size(impl_->pass("clouds").program, "AtmosphereBlock"); }
int GlRenderer::atmosphere_block_offset(const std::string& member) const {
  return member_offset(impl_->pass("clouds").program, "u_atmo." + member);
}

std::vector<glm::vec3> GlRenderer::transmittance_dump(const AtmosphereSettings& a, double* precompute_ms) {
  Impl& m = *impl_;
  m.resize(std::max(m.w, 1), std::max(m.h, 1));
  bool dirty = m.atmosphere_dirty(a);
  FrameSetup none;
  GLuint q[2];
  glCreateQueries(GL_TIMESTAMP, 2, q);
  glQueryCounter(q[0], GL_TIMESTAMP);
  for (Pass& p : m.passes)
    if (p.precompute) m.run_lut(p, none, dirty);
  glQueryCounter(q[1], GL_TIMESTAMP);
  // The grid through the shaders' lookup (atmosphere_dump.frag) into a scratch target.
  GLuint prog = link_program(m.shaders, "fullscreen.vert", "atmosphere_dump.frag");
  GLuint tex = make_texture_2d(GL_RGBA32F, kDumpMus, kDumpAltitudes), fbo = 0;
  glCreateFramebuffers(1, &fbo);
  glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, tex, 0);
  std::vector<glm::vec4> px(size_t(kDumpMus) * kDumpAltitudes);
  try {
    check_fbo(fbo, "transmittance dump");
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, kDumpMus, kDumpAltitudes);
    glUseProgram(prog);
    glProgramUniform2i(prog, 0, kDumpMus, kDumpAltitudes);
    glBindVertexArray(m.vao_empty);
    glDisable(GL_BLEND);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, kDumpMus, kDumpAltitudes, GL_RGBA, GL_FLOAT, px.data());
  } catch (...) {
    glDeleteFramebuffers(1, &fbo), glDeleteTextures(1, &tex), glDeleteProgram(prog), glDeleteQueries(2, q);
    throw;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo), glDeleteTextures(1, &tex), glDeleteProgram(prog);
  GLuint64 t[2] = {0, 0};
  glGetQueryObjectui64v(q[0], GL_QUERY_RESULT, &t[0]);
  glGetQueryObjectui64v(q[1], GL_QUERY_RESULT, &t[1]);
  glDeleteQueries(2, q);
  if (precompute_ms) *precompute_ms = double(t[1] - t[0]) * 1e-6;
  GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw GlError("OpenGL error 0x" + std::to_string(err) + " in the transmittance dump");
  std::vector<glm::vec3> out;
  for (const glm::vec4& v : px) out.emplace_back(v);
  return out;
}

RendererStats GlRenderer::stats() const {
  RendererStats st;
  st.light_volume_builds = impl_->light_builds;
  st.shadow_map_builds = impl_->shadow_builds;
  st.ground_draws = impl_->ground_draws;
  st.air_lut_builds = impl_->air_builds;
  st.program_count = int(impl_->program_cache.size());
  st.ms_volume_builds = impl_->ms_builds;
  st.nano_grids_on_gpu = impl_->grids_up;
  return st;
}
void GlRenderer::set_ground_reuse(bool on) { impl_->ground_reuse = on; }

MsDiffusionResult GlRenderer::last_ms_solve() const { return impl_->ms_last; }

int GlRenderer::lut_computations(const std::string& pass) const { return impl_->pass(pass).runs; }

std::vector<std::string> GlRenderer::pass_names() const {
  std::vector<std::string> names;
  for (const Pass& p : impl_->passes) names.push_back(p.name);
  return names;
}

FrameImages GlRenderer::read_back() {
  Impl& m = *impl_;
  FrameImages out{Image(m.w, m.h), Image(m.w, m.h)};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.target("final").fbo[0]);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, m.w, m.h, GL_RGBA, GL_FLOAT, out.display.rgba.data());
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, m.w, m.h, GL_RGBA, GL_FLOAT, out.linear.rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  return out;
}

Image GlRenderer::read_target(const std::string& name, int attachment) {
  Impl& m = *impl_;
  // The frame's own copy of a history target is "@prev" once render() has swapped.
  const Target& t = m.target(name);
  const int copy = t.history ? 1 : 0;
  if (t.volume_size || attachment < 0 || size_t(attachment) >= t.tex[size_t(copy)].size())
    throw GlError("read_target: '" + name + "' has no 2D attachment " + std::to_string(attachment));
  Image out(t.w, t.h);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo[copy]);
  glReadBuffer(GLenum(GL_COLOR_ATTACHMENT0 + attachment));
  glReadPixels(0, 0, t.w, t.h, GL_RGBA, GL_FLOAT, out.rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  return out;
}

void GlRenderer::present(int ww, int wh) {
  Impl& m = *impl_;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.target("final").fbo[0]);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, m.w, m.h, 0, 0, ww, wh, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void GlRenderer::present_image(const Image& img, int ww, int wh) {
  Impl& m = *impl_;
  if (img.width < 1 || img.height < 1) return;
  if (img.width != m.image_w || img.height != m.image_h) {
    if (m.fbo_image) glDeleteFramebuffers(1, &m.fbo_image);
    if (m.tex_image) glDeleteTextures(1, &m.tex_image);
    glCreateTextures(GL_TEXTURE_2D, 1, &m.tex_image);
    glTextureStorage2D(m.tex_image, 1, GL_RGBA32F, img.width, img.height);
    glCreateFramebuffers(1, &m.fbo_image);
    glNamedFramebufferTexture(m.fbo_image, GL_COLOR_ATTACHMENT0, m.tex_image, 0);
    m.image_w = img.width, m.image_h = img.height;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(m.tex_image, 0, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT, img.rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo_image);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, img.width, img.height, 0, 0, ww, wh, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

Image GlRenderer::read_window(int ww, int wh) {
  Image img(ww, wh);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, ww, wh, GL_RGBA, GL_FLOAT, img.rgba.data());
  return img;
}

}  // namespace cloudviewer
