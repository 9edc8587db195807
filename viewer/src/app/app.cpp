#include "cloudviewer/controls.h"
#include "cloudviewer/app.h"

#include "cloudgen/printable.h"
#include "cloudgen/exit_codes.h"
#include "cloudgen/help_text.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cmath>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cloudgen/exit_codes.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/output.h"
#include "cloudviewer/atmosphere_luts.h"
#include "cloudviewer/errors.h"
#include "cloudgen/view.h"
#include "cloudviewer/lod.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/noise_cache.h"
#include "cloudgen/preset.h"
#endif
#include "scene/default_view.h"
#include "app/session.h"
#include "internal.h"

namespace cloudviewer {
namespace {

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// Every number entering from the command line is finite and inside its range; the message names
// the flag, the value and the range.
constexpr double kMaxCoordinate = 1e8;  // m: camera and target positions (100,000 km)

std::vector<double> parse_numbers(const std::string& flag, const std::string& text, size_t count, double lo,
                                  double hi) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    double d = 0;
    try {
      d = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(d))
      throw InputError(flag + " " + text + ": '" + item + "' is not a finite number");
    if (d < lo || d > hi)
      throw InputError(flag + " " + text + ": " + item + " is out of range [" + format_number(lo) + ", " +
                       format_number(hi) + "]");
    v.push_back(d);
  }
  if (v.size() != count)
    throw InputError(flag + " " + text + ": expected " + std::to_string(count) + " comma-separated numbers");
  return v;
}

Camera parse_camera(const std::string& text, double fov) {
  auto colon = text.find(':');
  if (colon == std::string::npos) throw InputError("--camera " + text + ": expected EX,EY,EZ:TX,TY,TZ");
  auto e = parse_numbers("--camera", text.substr(0, colon), 3, -kMaxCoordinate, kMaxCoordinate);
  auto t = parse_numbers("--camera", text.substr(colon + 1), 3, -kMaxCoordinate, kMaxCoordinate);
  Camera c;
  c.eye = glm::dvec3(e[0], e[1], e[2]);
  c.target = glm::dvec3(t[0], t[1], t[2]);
  c.fov_y_deg = fov;
  if (glm::length(c.target - c.eye) < 1e-6) throw InputError("--camera " + text + ": eye and target coincide");
  return c;
}

void parse_size(const std::string& text, int& w, int& h) {
  auto x = text.find('x');
  bool ok = x != std::string::npos;
  if (ok) {
    try {
      size_t u1 = 0, u2 = 0;
      w = std::stoi(text.substr(0, x), &u1);
      h = std::stoi(text.substr(x + 1), &u2);
      ok = u1 == x && u2 == text.size() - x - 1;
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok || w < 1 || h < 1 || w > 16384 || h > 16384)
    throw InputError("--size " + text + ": expected WIDTHxHEIGHT, each 1..16384");
}

// --out for frame i: a printf-style "%d" / "%0Nd" (one, N <= 9) becomes the frame number; "%%" is a
// literal percent; a name without a pattern is used as it is. Throws InputError on anything else.
std::string frame_file_name(const std::string& out, int frame) {
  std::string r;
  int conversions = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] != '%') {
      r += out[i];
      continue;
    }
    if (i + 1 < out.size() && out[i + 1] == '%') {
      r += '%';
      ++i;
      continue;
    }
    size_t j = i + 1;
    int width = 0;
    bool zero = j < out.size() && out[j] == '0';
    if (zero) ++j;
    if (j < out.size() && out[j] >= '1' && out[j] <= '9') width = out[j++] - '0';
    if (j >= out.size() || out[j] != 'd' || ++conversions > 1)
      throw InputError("--out " + out + ": the frame pattern must be one %d or %0Nd (N = 1..9); write %% for a "
                       "literal percent");
    std::string num = std::to_string(frame);
    if (int(num.size()) < width) num = std::string(size_t(width) - num.size(), zero ? '0' : ' ') + num;
    r += num;
    i = j;
  }
  return r;
}

// A progress bar on stderr for long CPU work, redrawn at most every 1% (thread-safe).
class ProgressBar {
 public:
  ProgressBar(std::ostream& err, std::string what) : err_(err), what_(std::move(what)) {}
  void update(int done, int total) {
    std::lock_guard<std::mutex> lock(mutex_);
    int pct = total > 0 ? done * 100 / total : 100;
    if (pct == last_) return;
    last_ = pct;
    int bar = pct * 30 / 100;
    err_ << "\r" << what_ << " [" << std::string(size_t(bar), '#') << std::string(size_t(30 - bar), ' ') << "] "
         << pct << "%" << std::flush;
  }
  void finish() {
    if (last_ >= 0) err_ << "\n";
  }

 private:
  std::ostream& err_;
  std::string what_;
  std::mutex mutex_;
  int last_ = -1;
};

std::string params_help() {
  std::string s = "render parameters (--set render.KEY=VALUE):\n";
  RenderSettings d;
  for (const ParamDef& p : render_params())
    s += cloudgen::help_entry(p.key + " (" + p.type + ", " + p.range + ", default " + p.get(d) + ")", p.doc);
  return s + atmosphere_params_help() + cloudgen::motion_help();
}

// --lighting-json: the light the default view of INPUT puts on its cloud, for renderers that must
// match the preview (cloudgen blender): the sun's direction (world, y up), its colour at the
// volume's centre (the atmosphere's transmittance with render.sky=precomputed, the constant sun
// colour with the analytic sky) and intensity, the isotropic ambient from above and below (the
// marcher mixes them by height) with its scale.
int write_lighting_json(const Options& o, const std::string& path, std::ostream& out) {
  const PreparedVolume vol = open_input(o.input, o.settings);
  const int w = o.width > 0 ? o.width : 320, h = o.height > 0 ? o.height : 180;
  const Camera cam = resolve_camera(o, vol, w, h);
  const Sun sun = resolve_sun(o, cam);
  const FrameSetup f = make_frame(vol, o.settings, cam, sun, w, h);
  const ref::CloudParams& p = f.params;
  glm::dvec3 sun_color = p.sun_color;
  const bool precomputed = o.settings.sky == SkyMode::Precomputed;
  if (precomputed) {
    const std::shared_ptr<const AtmosphereLuts> luts = shared_atmosphere_luts(o.settings.atmosphere);
    const double ground_y = cam.eye.y - p.sky_altitude_m;
    const double r = o.settings.atmosphere.bottom_radius + std::max(vol.center().y - ground_y, 0.0);
    sun_color *= luts->sun_transmittance(r, glm::normalize(sun.direction()).y);
  }
  auto arr = [](const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  nlohmann::json j = {{"sky", precomputed ? "precomputed" : "analytic"},
                      {"sun_direction", arr(glm::normalize(sun.direction()))},
                      {"sun_color", arr(sun_color)},
                      {"sun_intensity", p.sun_radiance},
                      {"ambient_above", arr(p.ambient_color)},
                      {"ambient_below", arr(p.ambient_below_color)},
                      {"ambient_scale", p.ambient_scale}};
  cloudgen::atomic_write(path, [&](const std::string& tmp) {
    cloudgen::write_file_stream(tmp, [&](std::ostream& os) { os << j.dump(2) << "\n"; });
  });
  out << "wrote " << cloudgen::printable(path) << "\n";
  return 0;
}

// --dump-lut transmittance: the LUT through the shaders' lookup, from the GPU textures (gl) or the
// double-precision reference (cpu), as `h_m,mu,r,g,b` rows.
int dump_atmosphere_lut(const Options& o, std::ostream& out) {
  if (o.out.empty()) throw InputError("--dump-lut needs --out FILE.csv");
  std::vector<glm::dvec3> values;
  auto t0 = std::chrono::steady_clock::now();
  if (o.backend == "cpu") {
    values = transmittance_dump_cpu(o.settings.atmosphere);
    out << "cpu reference: transmittance LUT " << CV_TRANSMITTANCE_W << "x" << CV_TRANSMITTANCE_H << " in "
        << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  } else {
    HeadlessContext ctx;
    GlRenderer renderer{ShaderSource(o.shader_dir)};
    double ms = 0;
    for (const glm::vec3& v : renderer.transmittance_dump(o.settings.atmosphere, &ms)) values.emplace_back(v);
    out << ctx.description() << "\ngpu: transmittance LUT " << CV_TRANSMITTANCE_W << "x" << CV_TRANSMITTANCE_H
        << " in " << ms << " ms\n";
  }
  write_transmittance_csv(o.out, o.settings.atmosphere, values);
  out << "wrote " << cloudgen::printable(o.out) << "\n";
  return 0;
}

// The command line's words beside Options: texts parsed after CLI11, and the flags that print a
// reference and exit.
struct CliText {
  std::string size, camera, fov, sun, time, dump_lut, lighting_json;
  bool help_params = false, params_md = false, keys_md = false, atmo_md = false, motion_md = false;
};

void add_options(CLI::App& app, Options& o, CliText& t) {
  app.add_option("input", o.input,
                 "volume to view: .vdb, .nvdb, .raw/.json, .ktx2 (cloudgen), a preset .json, or synthetic:sphere|slab|blob|noise");
  app.add_flag("--headless", o.headless, "render without a display through EGL and exit");
  app.add_option("--size", t.size, "image size WIDTHxHEIGHT (default 320x180 headless, 1280x720 window)");
  app.add_option("--camera", t.camera, "camera EX,EY,EZ:TX,TY,TZ in world metres (default: frames the volume)");
  app.add_option("--fov", t.fov, "vertical field of view in degrees, 1..170 (default 60)");
  app.add_option("--sun", t.sun, "sun AZIMUTH,ELEVATION in degrees (azimuth clockwise from -z; default behind the viewer)");
  app.add_option("--set", o.sets, "render.KEY=VALUE, atmosphere.KEY=VALUE or motion.KEY=VALUE (see --help-params); "
                 "with a preset .json INPUT also the preset's own keys as `cloudgen generate --set` spells them "
                 "(threshold=0.4, coverage.low=0.2), applied before it is generated")->take_all();
  app.add_option("--edit", o.edits, "headless, a preset INPUT: a preset KEY=VALUE (as --set) applied after the first "
                 "generation, the edits one after another, each regeneration timed; the noise is kept, so a threshold, "
                 "coverage, density, height or tower edit does not evaluate it again. The image is the last edit's "
                 "(the same as --set of all of them). In a window with --out: applied through the panel's edit after the first "
                 "frame, then the frame is written once the regeneration is shown")->take_all();
  app.add_option("--dump-lut", t.dump_lut, "write an atmosphere LUT read through the shaders' lookup to --out as CSV (no INPUT needed)")
      ->check(CLI::IsMember({"transmittance"}));
  app.add_flag("--stats", o.stats,
               "headless: also print every pass's GPU time and each atmosphere LUT's precompute time (GPU "
               "pass and CPU reference)");
  app.add_option("--lighting-json", t.lighting_json,
                 "write the default view's lighting of INPUT as JSON (sun direction and colour at the volume's "
                 "centre, ambient from above and below; what `cloudgen blender` matches) and exit");
  app.add_option("--out", o.out, "headless output image (.png tone-mapped sRGB, .exr linear HDR); with --frames, a "
                 "printf pattern such as frame_%04d.png writes every frame, a plain name only the last");
  app.add_option("--time", t.time, "the clouds' time in seconds: wind and flow map move them (motion.*, see "
                 "--help-params); 0 = the static volume");
  app.add_option("--frames", o.frames, "headless: render N frames, the time advancing 1/FPS per frame from --time "
                 "and the jitter pattern per frame")->check(CLI::Range(1, 1000000));
  app.add_option("--fps", o.fps, "frames per second for --frames (0 holds the time still, e.g. to converge "
                 "render.temporal; default 24)")->check(CLI::Range(0.0, 10000.0));
  app.add_option("--backend", o.backend, "gl (OpenGL), cpu (the double-precision reference of the same shader math) or "
                 "pathtrace (the ground truth for the lighting: every order of scattering, Monte Carlo)")
      ->check(CLI::IsMember({"gl", "cpu", "pathtrace"}));
  app.add_option("--spp", o.spp, "--backend pathtrace: paths per pixel (noise falls as 1/sqrt(spp); default 64). Beside --out it writes "
                 "NAME.stderr.exr, the per-pixel standard error of the linear radiance")
      ->check(CLI::Range(1, 1 << 20));
  app.add_option("--shader-dir", o.shader_dir, "read shaders from this directory instead of the embedded copies (hot reload)");
  app.add_option("--mie-table", o.mie_table, "Mie phase table to use for render.phase=mie (text: one value per line over 0..180 degrees, or 'theta value' columns)");
  app.add_option("--bench", o.bench, "benchmark camera track (JSON, see viewer/tracks/default.json)");
  app.add_option("--csv", o.csv, "benchmark per-frame results as CSV");
  app.add_option("--bench-reference", o.bench_reference, "also render each track frame with the CPU reference at this step count and report RMSE");
  app.add_option("--bench-repeat", o.bench_repeat, "timing rounds over all configurations and frames (best of N per frame)")->check(CLI::Range(1, 100));
  app.add_flag("--help-params", t.help_params, "list every render.KEY with type, range, default and meaning");
  app.add_flag("--params-markdown", t.params_md, "the render.KEY table as Markdown (docs/reference/viewer-params.md)");
  app.add_flag("--atmosphere-markdown", t.atmo_md, "the atmosphere.KEY table as Markdown (docs/reference/viewer-params.md)");
  app.add_flag("--motion-markdown", t.motion_md, "the motion.KEY table as Markdown (docs/reference/viewer-params.md)");
  app.add_flag("--keys-markdown", t.keys_md, "the window's parameter key bindings as Markdown (docs/reference/viewer-params.md)");
}

// A key of the viewer's settings: render.*, atmosphere.*, motion.* or a bare render key.
bool is_viewer_key(const std::string& assignment) {
  const std::string key = assignment.substr(0, assignment.find('='));
  for (const char* prefix : {"render.", "atmosphere.", "motion."})
    if (key.rfind(prefix, 0) == 0) return true;
  for (const ParamDef& p : render_params())
    if (p.key == key) return true;
  return false;
}

// A --set key of the preset rather than of the viewer: not a viewer key, and its first part a
// top-level key of the preset table.
bool is_preset_key(const std::string& assignment) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  if (is_viewer_key(assignment)) return false;
  const std::string key = assignment.substr(0, assignment.find('='));
  const std::string top = key.substr(0, key.find('.'));
  for (const cloudgen::ParamInfo& p : cloudgen::params())
    if (p.pointer.substr(1, p.pointer.find('/', 1) - 1) == top) return true;
#else
  (void)assignment;
#endif
  return false;
}

// --set's preset keys go to the preset (checked when it is loaded), the others to the settings.
void sort_sets(Options& o) {
  std::vector<std::string> viewer;
  for (std::string& a : o.sets) (is_preset_key(a) ? o.preset_sets : viewer).push_back(std::move(a));
  o.sets = std::move(viewer);
}

// --edit, before anything is generated: headless, a preset INPUT, and every edit in turn a valid
// preset (the message names the edit, the key, the value and what is allowed).
void check_edits(const Options& o) {
  if (o.edits.empty()) return;
  if (!o.headless && o.out.empty())
    throw InputError("--edit needs --headless (it times regenerations and writes the last image), or a window with "
                     "--out (the edits go through the panel's edit after the first frame, then the frame is written)");
  if (!o.bench.empty()) throw InputError("--edit and --bench do not go together");
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  std::string ext = std::filesystem::path(o.input).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".json") throw InputError("--edit " + o.edits.front() + ": the input '" + o.input + "' is not a preset .json");
  std::vector<std::string> sets = o.preset_sets;
  for (const std::string& e : o.edits) {
    if (e.find('=') == std::string::npos) throw InputError("--edit " + e + ": expected KEY=VALUE");
    if (is_viewer_key(e))  // anything else goes to the preset reader (unknown keys: a did-you-mean)
      throw InputError("--edit " + e + ": not a preset key (--edit takes the preset's keys, as cloudgen generate "
                       "--set spells them; render.*, atmosphere.* and motion.* go with --set)");
    if (e.rfind("view.", 0) == 0) throw InputError("--edit " + e + ": the view is not an edit of the volume; use --set");
    sets.push_back(e);
    try {
      cloudgen::load_preset(o.input, sets);
    } catch (const cloudgen::InputError& x) {
      throw InputError("--edit " + e + ": " + x.what());
    }
  }
#else
  throw InputError("--edit: this cloudviewer was built without the cloudgen library");
#endif
}

// --help-params and the Markdown tables: printed, and true, when one was asked for.
bool print_reference(const CliText& t, std::ostream& out) {
  if (t.help_params) out << params_help();
  else if (t.atmo_md) out << atmosphere_params_markdown();
  else if (t.motion_md) out << cloudgen::motion_markdown();
  else if (t.params_md || t.keys_md) out << (t.params_md ? params_markdown() : key_help_markdown());
  else return false;
  return true;
}

// The view, size and time from the command line's texts (after --set), over the input's own view.
void resolve_view_options(Options& o, const CliText& t, bool fov_given) {
  if (!t.fov.empty()) o.fov = parse_numbers("--fov", t.fov, 1, 1, 170)[0];
  if (!o.mie_table.empty()) o.settings.mie_table = read_mie_table(o.mie_table);
  if (!t.size.empty()) parse_size(t.size, o.width, o.height);
  else if (o.headless) o.width = 320, o.height = 180;
  else o.width = 1280, o.height = 720;
  if (!t.camera.empty()) o.camera = parse_camera(t.camera, o.fov);
  if (!t.sun.empty()) {
    auto v = parse_numbers("--sun", t.sun, 2, -360, 360);
    if (v[1] < -90 || v[1] > 90) throw InputError("--sun " + t.sun + ": elevation must be in [-90, 90]");
    o.sun = Sun{v[0], v[1]};
  }
  if (o.bench.empty()) apply_input_view(o, fov_given);  // the input's preset/metadata view
  if (!t.time.empty()) o.settings.time = parse_numbers("--time", t.time, 1, -1e7, 1e7)[0];
}

// Headless output: fail on a bad extension or pattern before rendering.
void check_headless_out(const Options& o) {
  if (o.out.empty() && o.bench.empty()) throw InputError("--headless needs --out FILE or --bench TRACK.json");
  if (o.out.empty()) return;
  frame_file_name(o.out, 0);
  std::string lower = o.out;
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (!(lower.size() > 4 && (lower.substr(lower.size() - 4) == ".png" || lower.substr(lower.size() - 4) == ".exr")))
    throw InputError("--out " + o.out + ": unknown image type (allowed: .png, .exr)");
}

void report_volume(const Options& o, const PreparedVolume& vol, double load_s, std::ostream& out) {
  out << "volume " << vol.dims[0] << "x" << vol.dims[1] << "x" << vol.dims[2] << " voxels of "
      << vol.voxel_size << " m" << (vol.tiles ? " (tiles in x,z)" : "") << ", occupancy "
      << vol.occ_dims[0] << "x" << vol.occ_dims[1] << "x" << vol.occ_dims[2] << " cells, "
      << std::lround(vol.occupied_fraction * 100) << "% occupied, loaded in "
      << load_s << " s; " << (vol.nano ? "nanovdb" : "dense") << " volume, ";
  auto mib = [](uint64_t b) {  // one decimal; "<0.1" rather than 0 for a few KiB
    const double m = std::round(double(b) / (1 << 20) * 10) / 10.0;
    return b > 0 && m == 0 ? std::string("<0.1") : (std::ostringstream() << m).str();
  };
  const bool atlas = vol.nano && o.backend == "gl" && o.settings.nanovdb_lookup == NanoLookup::Atlas;
  if (atlas)
    out << mib(nano_grid_bytes(vol)) << " MiB of grids on the CPU, " << mib(volume_gpu_bytes(vol, NanoLookup::Atlas))
        << " MiB on the GPU and the brick atlas (its size follows when it is built)\n";
  else
    out << mib(volume_gpu_bytes(vol, o.settings.nanovdb_lookup)) << " MiB on the GPU\n";
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

FrameImages render_pathtrace_frame(const Options& o, const Session& session, const FrameSetup& frame, int frame_index,
                                   Image& standard_error, const std::string& label, std::ostream& out,
                                   std::ostream& err) {
  auto r0 = std::chrono::steady_clock::now();
  PathTraceOptions po;
  po.spp = o.spp;
  po.seed = uint32_t(frame_index + 1);
  po.standard_error = &standard_error;
  ProgressBar bar(err, "path tracing " + std::to_string(o.width) + "x" + std::to_string(o.height) + " at " +
                           std::to_string(o.spp) + " spp");
  po.progress = [&bar](int done, int rows) { bar.update(done, rows); };
  FrameImages img = render_pathtrace(session.volume(), frame, po);
  bar.finish();
  out << label << "path tracer: " << o.width << "x" << o.height << " at " << o.spp << " spp in " << seconds_since(r0)
      << " s\n";
  return img;
}

// What the GL frame did (the renderer's counters before it: a rebuild shows as a new count).
void report_gl_frame(const Options& o, const Session& session, const FrameSetup& frame, const GpuTimings& t,
                     const RendererStats& before, const std::string& label, std::ostream& out) {
  const GlRenderer& renderer = *session.renderer();
  out << label << "gpu: " << o.width << "x" << o.height << " total " << t.total_ms << " ms (atmosphere LUTs "
      << t.atmosphere_ms << ", ground " << t.ground_ms << ", clouds " << t.cloud_ms << ", post " << t.post_ms << ")\n";
  if (renderer.stats().shadow_map_builds > before.shadow_map_builds)  // (the pass's timer reads a few ns even when it is skipped)
    out << label << "gpu: ground shadow map " << frame.params.shadow_map_nx << "x" << frame.params.shadow_map_nz
        << " texels of " << frame.params.shadow_map_texel_m << " m built in " << t.shadow_map_ms << " ms\n";
  if (t.programs_linked > 0)  // the driver's compile is seconds on some GPUs: say where a first frame's time went
    out << label << "gpu: compiled " << t.programs_linked << " GL programs in " << t.compile_ms
        << " ms (wall clock, not in the frame's time; each new set of render.compiled_modes compiles once)\n";
  if (t.atmosphere_ms > 0) {  // the LUTs were recomputed this frame: each one's time
    out << label << "gpu: atmosphere LUTs:";
    for (const auto& p : t.passes)
      // (the orders loop's passes are timed inside atmosphere_orders)
      if (p.first.rfind("atmosphere_", 0) == 0 && p.first.rfind("atmosphere_orders_", 0) != 0)
        out << " " << p.first.substr(11) << " " << p.second << " ms";
    out << "\n";
  }
  if (o.stats) {
    out << label << "gpu passes:";
    for (const auto& p : t.passes) out << " " << p.first << " " << p.second << " ms;";
    out << "\n";
  }
  if (o.stats && frame.params.ms_volume_on > 0.5 && renderer.stats().ms_volume_builds > before.ms_volume_builds) {
    const MsDiffusionResult ms = renderer.last_ms_solve();
    out << label << "ms volume: " << frame.params.ms_volume_dims.x << "x" << frame.params.ms_volume_dims.y << "x"
        << frame.params.ms_volume_dims.z << " cells, " << ms.iterations << " iterations (+" << ms.coarse_iterations
        << " on coarser grids), " << (ms.converged ? "converged" : "NOT converged") << ", solved in "
        << ms.seconds * 1e3 << " ms on the CPU (inside the ms_volume pass's time)\n";
  }
}

// What the headless frames carry from one to the next.
struct HeadlessState {
  Image standard_error;  // --backend pathtrace: written beside each image
  RendererStats stats;  // the diffusion volume's solves and the ground shadow map's builds so far (a new one is reported)
};

// One frame with --backend: the image, and its report on `out`. `frame_index`: render.frame.
FrameImages render_frame(const Options& o, Session& session, const FrameSetup& frame, int frame_index,
                         HeadlessState& state, const std::string& label, std::ostream& out, std::ostream& err) {
  if (o.backend == "pathtrace")
    return render_pathtrace_frame(o, session, frame, frame_index, state.standard_error, label, out, err);
  GlRenderer* renderer = session.renderer();
  if (!renderer) {
    auto r0 = std::chrono::steady_clock::now();
    FrameImages img = render_cpu(session.volume(), frame);
    out << label << "cpu reference: " << o.width << "x" << o.height << " in " << seconds_since(r0) << " s\n";
    return img;
  }
  GpuTimings t;
  renderer->render(frame, &t);
  FrameImages img = renderer->read_back();
  report_gl_frame(o, session, frame, t, state.stats, label, out);
  state.stats = renderer->stats();
  return img;
}

// Stages frame i's image (and, with the path tracer, its standard error beside it) into `batch`;
// returns the "wrote" lines to print once the batch is published.
std::string stage_frame(const Options& o, int i, const FrameImages& img, const Image& standard_error,
                        ImageBatch& batch, std::ostream& err) {
  ImageStats st = image_stats(img.linear);
  if (st.nonfinite) err << "warning: " << st.nonfinite << " non-finite values in the image\n";
  std::string path = frame_file_name(o.out, i);
  if (o.backend == "pathtrace") {  // beside it, both or neither: the per-pixel standard error, linear
    const std::string se_path = path.substr(0, path.size() - 4) + ".stderr.exr";
    batch.stage({{path, &img.display, &img.linear}, {se_path, &standard_error, &standard_error}});
    return "wrote " + cloudgen::printable(path) + "\nwrote " + cloudgen::printable(se_path) +
           " (per-pixel standard error of the linear radiance before bloom)\n";
  }
  batch.stage({{path, &img.display, &img.linear}});
  return "wrote " + cloudgen::printable(path) + "\n";
}

std::string milliseconds(double seconds) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  os << seconds * 1e3 << " ms";
  return os.str();
}

// --edit: each edit joins the preset's sets, the volume is generated again from the kept noise,
// prepared and uploaded; one line each, with where the time went under --stats.
void apply_edits(const Options& o, Session& session, std::ostream& out) {
  for (size_t i = 0; i < o.edits.size(); ++i) {
    session.edit_preset(o.edits[i]);  // the panel's edit too
    InputTiming t;
    double upload_s = 0;
    const auto t0 = std::chrono::steady_clock::now();
    session.reopen(o.input, o.settings, &t, &upload_s);
    out << "edit " << i + 1 << "/" << o.edits.size() << " " << cloudgen::printable(o.edits[i]) << ": regenerated in "
        << milliseconds(seconds_since(t0));
    if (o.stats)
      out << " (generate " << milliseconds(t.load_s) << ", prepare " << milliseconds(t.prepare_s) << ", upload "
          << milliseconds(upload_s) << "; noise boxes " << t.noise_cached << " cached, " << t.noise_evaluated
          << " evaluated)";
    out << "\n";
  }
}

// --headless --out: --frames frames, each written (a pattern) or only the last (a plain name).
int render_headless(const Options& o, Session& session, std::ostream& out, std::ostream& err) {
  if (o.backend == "gl") out << session.start_headless(o.shader_dir) << "\n";
  apply_edits(o, session, out);  // before the camera: the default framing follows the volume
  Camera cam = resolve_camera(o, session.volume(), o.width, o.height);
  Sun sun = resolve_sun(o, cam);
  const bool pattern = o.out.find('%') != std::string::npos;
  RenderSettings s = o.settings;
  HeadlessState state;
  ImageBatch batch;  // every frame staged, then all published or none (docs/robustness.md)
  std::string wrote;
  for (int i = 0; i < o.frames; ++i) {
    // Frame i: the clouds' time advances 1/fps per frame, the jitter (and temporal) pattern by one.
    s.time = o.settings.time + (o.fps > 0 ? double(i) / o.fps : 0.0);
    s.frame = o.settings.frame + i;
    // The eroded distance field follows the frame's erosion and motion (a sequence that starts
    // still and then moves needs the up flow's slack).
    session.fit(s);
    FrameSetup frame = session.frame(s, cam, sun, o.width, o.height);
    std::string label = o.frames > 1 ? "frame " + std::to_string(i) + " (t = " + format_number(s.time) + " s): " : "";
    FrameImages img = render_frame(o, session, frame, s.frame, state, label, out, err);
    if (o.stats && i == 0 && s.sky == SkyMode::Precomputed) {
      const std::shared_ptr<const AtmosphereLuts> luts = shared_atmosphere_luts(s.atmosphere);
      out << "cpu: atmosphere LUTs: transmittance " << luts->seconds[0] * 1e3 << " ms, multiple_scattering "
          << luts->seconds[1] * 1e3 << " ms, irradiance " << luts->seconds[2] * 1e3
          << " ms (double; once per atmosphere, for the ambient light and the CPU reference)\n";
    }
    if (!pattern && i + 1 < o.frames) continue;  // a plain --out keeps only the last frame
    wrote += stage_frame(o, i, img, state.standard_error, batch, err);
  }
  batch.commit();
  out << wrote;
  return 0;
}

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Options o;
  CliText text;
  CLI::App app{"cloudviewer: real-time volumetric cloud ray marcher (OpenGL 4.5) with a CPU reference"};
  add_options(app, o, text);
  std::vector<std::string> argv_rest(args.begin() + (args.empty() ? 0 : 1), args.end());
  std::reverse(argv_rest.begin(), argv_rest.end());
  try {
    cloudgen::wrap_cli_help(app);
    cloudgen::check_cli_values(app);
    app.parse(argv_rest);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e, out, err);
    return code == 0 ? 0 : 1;
  }
  if (print_reference(text, out)) return 0;
  // Every file this run reads, before anything is written (the readers record them again).
  cloudgen::protect_input(o.input, "the input " + o.input);
  if (!o.bench.empty()) cloudgen::protect_input(o.bench, "the bench track " + o.bench);
  if (!o.mie_table.empty()) cloudgen::protect_input(o.mie_table, "the Mie table " + o.mie_table);
  sort_sets(o);
  for (const std::string& s : o.sets) apply_setting(o.settings, s);
  validate_atmosphere(o.settings.atmosphere);
  if (!text.dump_lut.empty()) return dump_atmosphere_lut(o, out);
  if (o.input.empty()) throw InputError("no INPUT given (try --help)");
  resolve_view_options(o, text, app.count("--fov") > 0);
  if (!text.lighting_json.empty()) return write_lighting_json(o, text.lighting_json, out);
  check_edits(o);
  if (!o.headless) return run_window(o, out, err);
  check_headless_out(o);
  auto t0 = std::chrono::steady_clock::now();
  const uint32_t level = choose_input_lod(o, out);
  PresetSource preset{o.preset_sets, nullptr};
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  cloudgen::NoiseCache noise;  // kept from the first generation for the edits
  if (!o.edits.empty()) preset.noise_cache = &noise;
#endif
  Session session(o.input, o.settings, level, preset);
  report_volume(o, session.volume(), seconds_since(t0), out);
  if (!o.bench.empty()) return run_bench(o, session, out, err);
  return render_headless(o, session, out, err);
}

}  // namespace

Camera resolve_camera(const Options& o, const PreparedVolume& vol, int width, int height) {
  if (o.camera) return *o.camera;
  return default_view_camera(vol, o.settings, o.fov, double(width) / height);
}

Sun resolve_sun(const Options& o, const Camera& cam) { return default_view_sun(o, cam); }

// render.sigma_t keeps the full-resolution grid's extinction, which by default follows the voxel size.
uint32_t choose_input_lod(Options& o, std::ostream& out) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  std::string ext = std::filesystem::path(o.input).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  std::error_code ec;
  if (ext != ".vdb" || o.settings.mode != PlaceMode::Box || !std::filesystem::is_regular_file(o.input, ec)) return 0;
  const cloudgen::SceneInfo info = cloudgen::read_scene_info(o.input);
  if (info.lod_levels == 0) return 0;
  const LodFile f = lod_file_of(info);
  Camera cam;
  if (o.camera) {
    cam = *o.camera;
  } else {  // default_view_camera's framing of the same box (the density's active box)
    const cloudgen::Framing fr =
        cloudgen::frame_box(info.origin, info.size(), o.fov, double(o.width) / std::max(o.height, 1));
    cam.eye = glm::dvec3(fr.eye[0], fr.eye[1], fr.eye[2]);
    cam.fov_y_deg = o.fov;
  }
  const LodPick pick = choose_lod(f, cam, o.height, o.settings);
  out << pick.describe(f, o.settings) << "\n";
  if (pick.level > 0 && !(o.settings.sigma_t > 0)) o.settings.sigma_t = cloudgen::default_extinction_per_metre(info.voxel_size);
  return pick.level;
#else
  (void)o, (void)out;
  return 0;
#endif
}

int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  cloudgen::InputScope inputs;  // no output of this run may replace a file it reads
  try {
    return run(args, out, err);
  } catch (...) {
    const std::exception_ptr e = std::current_exception();
    const int code = cloudgen::exit_code_of(e);
    std::string what = "unknown exception";
    try {
      std::rethrow_exception(e);
    } catch (const GlError& x) {
      err << "cloudviewer: OpenGL error: " << x.what() << "\n";
      return code;
    } catch (const std::exception& x) {
      what = x.what();
    } catch (...) {
    }
    err << "cloudviewer: " << cloudgen::exit_kind(code) << ": " << what << "\n";
    return code;
  }
}

}  // namespace cloudviewer
