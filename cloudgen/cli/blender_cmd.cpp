// `cloudgen blender`: a Blender scene (.blend) that renders a cloudgen VDB like cloudviewer's
// default view, built by Debian's headless `blender` with scripts/blender_scene.py. Every number of
// the scene (camera, sun, world, material, tone map) is computed here from the VDB's metadata and
// cloudgen/view.h, the definitions the viewer uses, and handed to the script as JSON.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "cloudgen/printable.h"
#include "cloudgen/sequence.h"
#include "cloudgen/view.h"
#include "commands.h"

extern char** environ;

namespace fs = std::filesystem;

namespace cloudgen::cli {
namespace {

struct BlenderArgs {
  std::string input, output, render, size = "640x360";
  std::vector<std::string> sets;
  int samples = 64;
  int volume_bounces = 4;  ///< multiple scattering, as the viewer's octaves approximate it (docs/blender.md)
  bool quiet = false;
  std::string frames;  ///< a VDB sequence (input with a # run): its frames A:B
  int64_t render_frame = -1;  ///< the frame --render renders (default: the first)
  uint32_t level = 0;  ///< the level of detail the volume's material reads (export.vdb.lod; 0 = full resolution)
};

/// The blender executable: $CLOUDGEN_BLENDER, else `blender` on PATH.
std::string find_blender() {
  if (const char* e = std::getenv("CLOUDGEN_BLENDER"); e && *e) {
    if (::access(e, X_OK) != 0) throw IoError(std::string("CLOUDGEN_BLENDER=") + e + ": not an executable file");
    return e;
  }
  const char* path = std::getenv("PATH");
  std::stringstream ss(path ? path : "");
  for (std::string dir; std::getline(ss, dir, ':');) {
    const fs::path p = fs::path(dir.empty() ? "." : dir) / "blender";
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  throw IoError("blender: not found on PATH; install Debian's package `blender` (apt-get install blender) "
                "or point CLOUDGEN_BLENDER at a Blender 3.x executable");
}

std::string script_path() {
  if (const char* e = std::getenv("CLOUDGEN_SCRIPT_DIR"); e && *e) return (fs::path(e) / "blender_scene.py").string();
  return std::string(CLOUD_SOURCE_DIR) + "/scripts/blender_scene.py";
}

/// Whether the file at `path` begins with the bytes of `magic`.
bool starts_with_bytes(const std::string& path, const std::string& magic) {
  std::ifstream in(path, std::ios::binary);
  std::string head(magic.size(), '\0');
  return in.read(&head[0], std::streamsize(head.size())) && head == magic;
}

/// Runs argv with stdout and stderr into `log`; returns the exit status (-1 when killed).
int run_logged(const std::vector<std::string>& argv, const std::string& log) {
  std::vector<char*> cargs;
  for (const auto& a : argv) cargs.push_back(const_cast<char*>(a.c_str()));
  cargs.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, cargs[0], &fa, nullptr, cargs.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw IoError(argv[0] + ": cannot start (" + std::strerror(rc) + ")");
  // Waited for by polling, so Ctrl-C ends Blender and this run well within the half second the
  // signal policy allows (cloudgen/interrupt.h); the staged temporaries are then discarded.
  int st = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &st, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw IoError(argv[0] + ": waitpid failed");
    if (g_cancel) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &st, 0);
      throw Cancelled();
    }
    ::usleep(5000);
  }
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string tail_of(const std::string& path, size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> all;
  for (std::string l; std::getline(in, l);) all.push_back(l);
  std::string out;
  for (size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) out += "  " + all[i] + "\n";
  return out;
}

/// y up (cloudgen, the viewer) -> Blender's z up: (x, y, z) -> (x, -z, y).
nlohmann::json zup(const Vec3& v) { return {v[0], -v[2], v[1]}; }

using nlohmann::json;

/// --size WIDTHxHEIGHT, each 1..16384.
std::array<int, 2> parse_size(const std::string& size) {
  int width = 0, height = 0;
  char x = 0;
  std::istringstream ss(size);
  if (!(ss >> width >> x >> height) || x != 'x' || !ss.eof() || width < 1 || height < 1 || width > 16384 ||
      height > 16384)
    throw InputError("--size " + size + ": expected WIDTHxHEIGHT, each 1..16384");
  return {width, height};
}

/// Checks the options that need no file; returns the render size.
std::array<int, 2> check_args(const BlenderArgs& a) {
  if (a.output.empty()) throw InputError("-o/--output: give the .blend file to write");
  if (fs::path(a.output).extension() != ".blend")
    throw InputError("-o " + a.output + ": the scene file must end in .blend");
  const std::array<int, 2> size = parse_size(a.size);
  if (a.samples < 1 || a.samples > 65536) throw InputError("--samples " + std::to_string(a.samples) + ": allowed 1..65536");
  if (a.volume_bounces < 0 || a.volume_bounces > 1024)
    throw InputError("--volume-bounces " + std::to_string(a.volume_bounces) + ": allowed 0..1024");
  if (!a.render.empty() && fs::path(a.render).extension() != ".png")
    throw InputError("--render " + a.render + ": the image must end in .png");
  return size;
}

/// The VDB the scene shows: the input's, the first frame of a sequence, or a preset's, generated.
/// The sibling OUT.vdb a preset input is generated into, in the .blend's transaction: Blender
/// reads it at its final path, so it is published first, and put back as it was (restored from a
/// hard link, or removed if it was new) unless the scene is written too.
class SiblingVdb {
 public:
  SiblingVdb() = default;
  SiblingVdb(const SiblingVdb&) = delete;
  SiblingVdb& operator=(const SiblingVdb&) = delete;
  SiblingVdb(SiblingVdb&& o) noexcept : path_(std::move(o.path_)), backup_(std::move(o.backup_)), armed_(o.armed_) {
    o.armed_ = false;
  }
  ~SiblingVdb() {
    if (!armed_) {
      if (!backup_.empty()) ::unlink(backup_.c_str());
      return;
    }
    if (!backup_.empty()) ::rename(backup_.c_str(), path_.c_str());
    else ::unlink(path_.c_str());
  }
  /// Before the VDB is written: a hard link to the file it will replace, if any.
  void keep(const std::string& path) {
    path_ = path;
    struct stat st;
    if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return;
    const fs::path p(path);
    backup_ = ((p.parent_path().empty() ? fs::path(".") : p.parent_path()) /
               ("." + p.filename().string().substr(0, 200) + ".bak-" + std::to_string(::getpid()) + "-blender"))
                  .string();
    if (::link(path.c_str(), backup_.c_str()) != 0) backup_.clear();
  }
  /// The VDB was written: from now on it is put back unless commit() is reached.
  void arm() { armed_ = true; }
  /// The scene was written: the new VDB stays.
  void commit() {
    if (armed_ && !backup_.empty()) ::unlink(backup_.c_str());
    armed_ = false;
  }

 private:
  std::string path_, backup_;
  bool armed_ = false;
};

struct SceneInput {
  std::string vdb;
  bool sequence = false;
  FrameRange seq;
  SiblingVdb sibling;
};

SceneInput scene_input(const BlenderArgs& a) {
  // A VDB sequence (cloud_####.vdb --frames A:B, as `generate --frames` writes it): the scene is
  // framed on its first frame and Blender plays the files as a volume sequence.
  SceneInput in{a.input, has_frame_pattern(a.input), {}, {}};
  if (in.sequence != !a.frames.empty())
    throw InputError(in.sequence ? a.input + ": a VDB sequence (# in the name) needs --frames A:B, the frames to play"
                                 : "--frames: only for a VDB sequence input such as out/cloud_####.vdb");
  if (a.render_frame >= 0 && !in.sequence) throw InputError("--render-frame: only for a VDB sequence input");
  if (in.sequence) {
    in.seq = parse_frames(a.frames);
    if (a.render_frame >= 0 && (a.render_frame < in.seq.first || a.render_frame > in.seq.last))
      throw InputError("--render-frame " + std::to_string(a.render_frame) + ": outside --frames " + a.frames);
    for (int64_t f = in.seq.first; f <= in.seq.last; ++f)
      if (!fs::exists(frame_path(a.input, f)))
        throw InputError(frame_path(a.input, f) + ": no such file (frame " + std::to_string(f) + " of --frames " +
                         a.frames + ")");
    in.vdb = frame_path(a.input, in.seq.first);
    if (!a.sets.empty())
      throw InputError("--set: only a preset input takes overrides; " + a.input + " is a VDB sequence");
  } else if (fs::path(a.input).extension() != ".vdb") {
    const std::string path = resolve_preset_path(a.input);
    Preset p = load_preset(path, a.sets);
    GenerateOptions go;
    go.cancel = &g_cancel;
    go.progress = progress_bar("generate", a.quiet);
    Volume v = generate(p, go);
    ExportOptions eo = p.export_options;
    in.vdb = fs::path(a.output).replace_extension(".vdb").string();
    in.sibling.keep(in.vdb);  // put back if the scene is not written (D12)
    write_vdb(v, in.vdb, eo);
    in.sibling.arm();
    if (!a.quiet) std::fprintf(stderr, "wrote %s (vdb)\n", printable(in.vdb).c_str());
  } else if (!a.sets.empty()) {
    throw InputError("--set: only a preset input takes overrides; " + a.input + " is a VDB");
  }
  return in;
}

/// The viewer's default view of a VDB (cloudviewer/src/default_view.cpp does the same): its
/// camera, sun and look, and the material's density scaling.
struct DefaultView {
  SceneInfo info;
  View view;
  Look look;
  Framing cam;
  double fov = 60, az = 0, el = 0;
  bool physical = false;  ///< densities in extinction per metre
  double extinction = 0, grid_scale = 1;
};

DefaultView default_view(const std::string& vdb, const BlenderArgs& a, std::array<int, 2> size_px) {
  DefaultView d;
  d.info = read_scene_info(vdb);
  d.view = view_of_metadata(d.info.metadata, vdb);
  d.look = look_of_view(d.view, vdb);
  // A tiling preset the viewer shows as an endless layer (stratus): Blender gets the one tile.
  for (const auto& kv : d.view.render)
    if (kv.first == "mode" && kv.second == "layer" && !a.quiet)
      std::fprintf(stderr,
                   "note: cloudviewer shows %s as a cloud layer repeated over the Earth (view.render.mode=layer); "
                   "this scene holds the one tile, framed from above like a box\n",
                   a.input.c_str());
  const Vec3 lo = d.info.origin, size = d.info.size();
  const Vec3 centre{lo[0] + 0.5 * size[0], lo[1] + 0.5 * size[1], lo[2] + 0.5 * size[2]};
  d.fov = d.view.fov.value_or(60.0);
  d.cam = d.view.eye ? Framing{*d.view.eye, d.view.target.value_or(centre)}
                     : frame_box(lo, size, d.fov, double(size_px[0]) / size_px[1]);
  d.az = d.view.sun_azimuth.value_or(sun_azimuth_behind(d.cam.eye, d.cam.target));
  d.el = d.view.sun_elevation.value_or(kDefaultSunElevation);
  for (auto& [k, val] : d.info.metadata)
    if (k == "density_units" && val == "extinction_per_metre") d.physical = true;
  d.extinction = d.look.extinction(d.info.voxel_size);
  if (d.physical) d.grid_scale = d.extinction;
  return d;
}

/// A temporary folder in /tmp, removed with everything in it.
struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/cloudgen-blender-XXXXXX";
    if (!::mkdtemp(tmpl)) throw IoError("cannot create a temporary folder in /tmp");
    path = tmpl;
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

struct Lighting {
  std::array<double, 3> sun_color, ambient;
  std::string source;  ///< what it came from, for the report
};

/// The viewer's lighting of its default view (its precomputed sky colours the sun and the ambient
/// light), asked of the cloudviewer built beside this cloudgen; without one, the analytic sky's
/// constants (what the viewer shows with render.sky=analytic).
Lighting viewer_lighting(const std::string& vdb, const Look& look, std::array<int, 2> size, const fs::path& work) {
  Lighting lit{{kSunColor[0], kSunColor[1], kSunColor[2]},
               {kAmbientColor[0] * look.ambient, kAmbientColor[1] * look.ambient, kAmbientColor[2] * look.ambient},
               "the analytic sky's constants (no cloudviewer beside cloudgen)"};
  std::error_code ec;
  const fs::path viewer = fs::read_symlink("/proc/self/exe", ec).parent_path() / "cloudviewer";
  if (ec || ::access(viewer.c_str(), X_OK) != 0) return lit;
  const std::string lj = (work / "lighting.json").string(), llog = (work / "lighting.log").string();
  std::vector<std::string> args{viewer.string(), vdb, "--lighting-json", lj, "--size",
                                std::to_string(size[0]) + "x" + std::to_string(size[1])};
  if (run_logged(args, llog) != 0)
    throw IoError(viewer.string() + " --lighting-json failed on " + vdb + "; its last lines:\n" + tail_of(llog, 8));
  std::ifstream in(lj);
  const json l = json::parse(in, nullptr, false);
  if (l.is_discarded() || !l.contains("sun_color") || !l.contains("ambient_above"))
    throw IoError(viewer.string() + " --lighting-json wrote no usable " + lj);
  const double scale = l.value("ambient_scale", look.ambient);
  for (int i = 0; i < 3; ++i) {
    lit.sun_color[size_t(i)] = l["sun_color"][size_t(i)].get<double>();
    lit.ambient[size_t(i)] = l["ambient_above"][size_t(i)].get<double>() * scale;
  }
  lit.source = "cloudviewer's " + l.value("sky", std::string("?")) + " sky";
  return lit;
}

/// The scene's sun, sky, ground and tone map.
void add_lighting(json& s, const DefaultView& d, const Lighting& lit) {
  const Look& look = d.look;
  s["sun"] = {{"direction", zup(sun_direction(d.az, d.el))},
              {"strength", look.sun_intensity},
              {"color", {lit.sun_color[0], lit.sun_color[1], lit.sun_color[2]}}};
  json horizon = json::array();
  for (int i = 0; i < 3; ++i) horizon.push_back(kSkyZenith[size_t(i)] + 0.55 * (1.0 - kSkyZenith[size_t(i)]));
  s["world"] = {{"ambient", {lit.ambient[0], lit.ambient[1], lit.ambient[2]}},
                {"zenith", {kSkyZenith[0], kSkyZenith[1], kSkyZenith[2]}},
                {"horizon", horizon}};
  s["ground"] = {{"enabled", look.ground},
                 {"height", std::min(0.0, d.info.origin[1])},
                 {"color", {kGroundColor[0] * look.ground_albedo / 0.18, kGroundColor[1] * look.ground_albedo / 0.18,
                            kGroundColor[2] * look.ground_albedo / 0.18}},
                 {"half_extent", 5e4}};
  s["tonemap"] = {{"exposure", look.exposure}, {"operator", look.tonemap}};
}

/// The scene description scripts/blender_scene.py builds (all but the files it writes).
json scene_description(const BlenderArgs& a, const SceneInput& in, const DefaultView& d, const Lighting& lit,
                       std::array<int, 2> size) {
  const Look& look = d.look;
  json s;
  // A level of detail (cloudgen generate --lod): its grids, with the full resolution's extinction
  // (the grids keep the density's integral, so the same Density gives the same cloud).
  const std::string suffix = a.level ? "_level_" + std::to_string(a.level) : "";
  const fs::path blend_abs = fs::absolute(a.output);
  s["vdb"] = fs::absolute(in.vdb).string();
  s["vdb_relative"] = "//" + fs::relative(fs::absolute(in.vdb), blend_abs.parent_path()).string();
  s["up"] = std::string(1, d.info.up);
  s["voxel_size"] = d.info.voxel_size;
  s["material"] = {{"density", d.physical ? 1.0 : d.extinction},
                   {"grid_scale", d.grid_scale},
                   {"anisotropy", look.phase == "none" ? 0.0 : look.g},
                   {"albedo", look.albedo},
                   {"erosion", look.erosion},
                   {"density_grid", a.level ? "density_level_" + std::to_string(a.level) : std::string("density")},
                   {"detail_grids", {"detail_g" + suffix, "detail_b" + suffix, "detail_a" + suffix}},
                   {"box_bottom", d.info.origin[1]},
                   {"box_height", d.info.size()[1]}};
  s["camera"] = {{"eye", zup(d.cam.eye)}, {"target", zup(d.cam.target)}, {"fov_y_deg", d.fov}};
  add_lighting(s, d, lit);
  if (in.sequence) {
    double fps = 24;
    bool loop = false;
    for (auto& [k, val] : d.info.metadata) {
      if (k == "fps") fps = std::strtod(val.c_str(), nullptr);
      if (k == "motion.loop") loop = val == "true" || val == "1";
    }
    if (!(fps > 0)) fps = 24;
    s["sequence"] = {{"first", in.seq.first},
                     {"count", in.seq.count()},
                     {"fps", fps},
                     {"loop", loop},
                     {"render_frame", a.render_frame >= 0 ? a.render_frame : in.seq.first}};
  }
  s["render"] = {{"width", size[0]},
                 {"height", size[1]},
                 {"samples", a.samples},
                 {"volume_bounces", a.volume_bounces},
                 {"max_bounces", std::max(8, a.volume_bounces + 4)},
                 {"volume_step_rate", 1.0},
                 {"volume_max_steps", 1024}};
  return s;
}

/// Runs Blender on scene `s`, writing the .blend (and the .png with --render), both published
/// together or neither.
void write_scene(const BlenderArgs& a, json& s, const std::string& blender, const std::string& script,
                 const fs::path& work) {
  const std::string scene_json = (work / "scene.json").string(), log = (work / "blender.log").string();
  auto run = [&](const std::string& tmp_blend, const std::string& tmp_png) {
    s["blend"] = fs::absolute(tmp_blend).string();
    s["render_png"] = tmp_png.empty() ? "" : fs::absolute(tmp_png).string();
    {
      std::ofstream out(scene_json);
      out << s.dump(2) << "\n";
      if (!out) throw IoError(scene_json + ": cannot write the scene description");
    }
    if (g_cancel) throw Cancelled();
    const int rc = run_logged({blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", script, "--",
                               scene_json},
                              log);
    if (g_cancel) throw Cancelled();
    // The temporaries exist before Blender runs (empty): what it wrote must start as its format does.
    if (rc != 0 || !starts_with_bytes(tmp_blend, "BLENDER") ||
        (!tmp_png.empty() && !starts_with_bytes(tmp_png, "\x89PNG\r\n\x1a\n")))
      throw IoError(blender + " failed (exit " + std::to_string(rc) + ") building " + a.output + "; its last lines:\n" +
                    tail_of(log, 15));
  };
  // Blender writes both files (and saves through "NAME@" + rename), so they are staged as named
  // temporaries in their folders and published together: both or neither.
  OutputBatch batch;
  batch.stage_named(a.output, [&](const std::string& tmp_blend) {
    if (a.render.empty()) run(tmp_blend, "");
    else batch.stage_named(a.render, [&](const std::string& tmp_png) { run(tmp_blend, tmp_png); });
  });
  if (g_cancel) throw Cancelled();
  batch.commit();
}

void run_blender(const BlenderArgs& a) {
  const std::array<int, 2> size = check_args(a);
  const std::string blender = find_blender();
  const std::string script = script_path();
  if (!fs::exists(script)) throw IoError(script + ": the Blender scene script is missing (set CLOUDGEN_SCRIPT_DIR)");
  SceneInput in = scene_input(a);
  const DefaultView d = default_view(in.vdb, a, size);
  if (a.level > d.info.lod_levels)
    throw InputError("--level: " + std::to_string(a.level) + " is not a level of detail of " + in.vdb +
                     "; allowed: 0 .. " + std::to_string(d.info.lod_levels) +
                     (d.info.lod_levels ? "" : " (write levels with cloudgen generate --lod N)"));
  const TempDir work;
  const Lighting lit = viewer_lighting(in.vdb, d.look, size, work.path);
  if (!a.quiet) std::fprintf(stderr, "lighting: %s\n", lit.source.c_str());
  json s = scene_description(a, in, d, lit, size);
  write_scene(a, s, blender, script, work.path);
  in.sibling.commit();
  if (!a.quiet) {
    std::fprintf(stderr, "wrote %s (Blender scene of %s)\n", printable(a.output).c_str(), printable(in.vdb).c_str());
    if (!a.render.empty())
      std::fprintf(stderr, "wrote %s (Cycles, %dx%d, %d samples)\n", printable(a.render).c_str(), size[0], size[1], a.samples);
  }
}

}  // namespace

void add_blender_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<BlenderArgs>();
  CLI::App* c = app.add_subcommand(
      "blender", "Write a Blender scene (.blend) that renders a VDB or preset like cloudviewer's default view.");
  c->add_option("input", a->input, "A cloudgen .vdb, or a preset (generated first into OUTPUT's name with .vdb)")->required();
  c->add_option("-o,--output", a->output, "The .blend to write")->required();
  c->add_option("--render", a->render, "Also render the scene with Cycles into this .png");
  c->add_option("--size", a->size, "Render size WIDTHxHEIGHT (also the camera's aspect; default 640x360)");
  c->add_option("--samples", a->samples, "Cycles samples per pixel (default 64)");
  c->add_option("--volume-bounces", a->volume_bounces, "Cycles volume bounces (default 4: the viewer's multiple-scattering octaves match 4 bounces' brightness to 2%; 0 = single scattering, 16 = all orders to 1%)");
  c->add_option("--set", a->sets, "Override a preset key, as for generate (preset inputs only)");
  c->add_flag("-q,--quiet", a->quiet, "No progress or summary");
  c->add_option("--frames", a->frames,
                "With a VDB sequence input (out/cloud_####.vdb from `generate --frames`): the frames A:B Blender plays "
                "as a volume sequence, with its velocity grid for motion blur (docs/motion.md)");
  c->add_option("--level", a->level,
                 "The level of detail the volume's material reads (density_level_N of a .vdb written with "
                 "generate --lod; 0 = full resolution, the default); in Blender, Principled Volume's Density Attribute");
  c->add_option("--render-frame", a->render_frame, "The frame of the sequence --render renders (default: the first)");
  c->footer("Runs Debian's `blender` headless (package blender; CLOUDGEN_BLENDER overrides the executable) with\n"
            "scripts/blender_scene.py. Example:\n"
            "  cloudgen blender cumulus -o out/cumulus.blend --render out/cumulus.png --size 320x180 --samples 32\n"
            "  cloudgen blender out/cloud_####.vdb --frames 0:47 -o out/cloud.blend \\\n"
            "      --render out/f12.png --render-frame 12");
  c->callback([a, &run] { run = [a] { run_blender(*a); }; });
}

}  // namespace cloudgen::cli
