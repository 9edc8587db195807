// Window mode: GLFW, OpenGL 4.5 core through libepoxy, orbit/fly camera, an on-screen Dear ImGui
// panel built from the parameter table (every render.* key, per-pass GPU times), keys and Shift + drag
// for the sun, Reset view and camera bookmarks,
// and the table's key bindings, GPU frame time in the title bar, F12 saves PNG + EXR, the input
// preset regenerates when its file changes, shaders hot-reload from --shader-dir.
#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>
#include <tuple>
#include <vector>

#include <epoxy/gl.h>
#include <GLFW/glfw3.h>

#include "cloudgen/motion.h"
#include "cloudgen/printable.h"
#include "cloudviewer/controls.h"
#include "cloudviewer/cpu_renderer.h"
#include "cloudviewer/settings.h"
#include "cloudviewer/errors.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/noise_cache.h"
#include "cloudgen/preset_fields.h"
#endif
#include "internal.h"
#include "app/authoring.h"
#include "app/panel.h"
#include "app/session.h"

namespace cloudviewer {
namespace {

namespace fs = std::filesystem;

fs::file_time_type mtime_of(const std::string& path) {
  std::error_code ec;
  auto t = fs::last_write_time(path, ec);
  return ec ? fs::file_time_type{} : t;
}

std::map<std::string, fs::file_time_type> dir_times(const std::string& dir) {
  std::map<std::string, fs::file_time_type> m;
  std::error_code ec;
  if (dir.empty()) return m;
  for (const auto& e : fs::directory_iterator(dir, ec)) m[e.path().string()] = mtime_of(e.path().string());
  return m;
}

// Where the camera is: the orbit camera around `pivot` (yaw/pitch in degrees, distance in metres)
// or the fly camera. What a bookmark and Reset view restore.
struct CameraPose {
  bool fly = false;
  glm::dvec3 pivot{0.0};
  double yaw = 0, pitch = 8, distance = 1000;
  glm::dvec3 fly_eye{0.0};
  double fly_yaw = 0, fly_pitch = 0;
};

struct ViewState : CameraPose {
  double move_speed = 100;
  double fov = 60;
  double last_x = 0, last_y = 0;
  bool dragging = false;
  bool sun_drag = false;   // Shift + drag: the sun follows the cursor
  bool sun_moved = false;  // a handle moved the sun since the last time it was kept as a preset edit
  CameraPose home;         // the start view: the preset's `view` (Reset view, Home)
  std::array<std::optional<CameraPose>, 9> bookmarks;  // Ctrl+1..9 / Shift+1..9, for this session
  PanelCamera* camera = nullptr;  // the camera requests of the keys and the panel
  bool save_requested = false;
  bool reload_requested = false;
  // The clouds' clock (motion.*): plays at time_scale x real time from --time.
  bool playing = true;
  double time_scale = 1;
  double start_time = 0;
  RenderSettings* settings = nullptr;
  Sun* sun = nullptr;
  std::ostream* out = nullptr;
  Panel* panel = nullptr;
  PanelFile* file = nullptr;  // a preset INPUT's file actions
};

glm::dvec3 forward_of(double yaw_deg, double pitch_deg) {
  double y = glm::radians(yaw_deg), p = glm::radians(pitch_deg);
  return glm::dvec3(std::cos(p) * std::sin(y), std::sin(p), std::cos(p) * std::cos(y));
}

Camera camera_of(const ViewState& v, double fov) {
  Camera c;
  c.fov_y_deg = fov;
  if (v.fly) {
    c.eye = v.fly_eye;
    c.target = v.fly_eye + forward_of(v.fly_yaw, v.fly_pitch);
  } else {
    c.target = v.pivot;
    c.eye = v.pivot - forward_of(v.yaw, -v.pitch) * v.distance;
  }
  return c;
}

// A parameter's value as the table spells it (enum names, true/false).
std::string value_of(const RenderSettings& s, const char* key) { return render_param(key).get(s); }

// Keys that are not render parameters; the parameter keys are the table's (key_bindings()).
const char* kWindowKeys =
    "| key | action |\n|---|---|\n"
    "| mouse drag, wheel | orbit (fly: look); zoom (fly: speed) |\n"
    "| `F` | orbit / fly; fly: W A S D, Q E down/up, Shift fast |\n"
    "| arrows | sun azimuth / elevation (a preset edit: Save as keeps it) |\n"
    "| `Shift` + drag | the sun to the sky under the cursor (azimuth, elevation -10..90; a preset edit: Save as keeps it) |\n"
    "| `Home` | reset view: the camera back to the preset's `view` (the start view) |\n"
    "| `Ctrl+1`..`9`, `Shift+1`..`9` | store, recall a camera bookmark (kept for this session only) |\n"
    "| `F1` | on-screen panel on / off |\n"
    "| `C` | the path tracer's reference image of this view in place of the preview (refined while nothing changes); `C` again: back |\n"
    "| `Space` | play / pause the clouds' motion (`motion.*`; starts at `--time`) |\n"
    "| `,` / `.` | motion time runs half / twice as fast (1/64x .. 1024x real time) |\n"
    "| `Backspace` | motion time back to `--time` |\n"
    "| `R` | reload shaders (from `--shader-dir`) and the input |\n"
    "| `F12` | save `cloudviewer_N.png` (tone-mapped) and `cloudviewer_N.exr` (linear HDR) |\n"
    "| `Ctrl+S` | a preset INPUT: save it with the panel's edits as the panel's file (atomic; never into presets/) |\n"
    "| `Ctrl+E` | a preset INPUT: export its VDB with the edits (as `cloudgen generate`) |\n"
    "| `Ctrl+B` | a preset INPUT: open the exported VDB in Blender (`cloudgen blender`; the .blend's path shown) |\n"
    "| `H`, `Esc` | this list, quit |\n";

std::string format_scale(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// A handle (arrows, Shift + drag) moved the sun: it leaves the time of day's path (render.time_of_day
// back to auto) and is kept as a preset edit once the mouse lets go (the frame loop).
void sun_by_hand(ViewState& v) {
  v.sun_moved = true;
  v.settings->time_of_day = -1;
}

// The sun under the window point (x, y) of a width x height window: the direction through it from
// the camera the frame is drawn with, the elevation kept to the handles' range.
void sun_to(ViewState& v, double x, double y, int width, int height) {
  if (width < 1 || height < 1) return;
  *v.sun = sun_toward(view_direction(camera_of(v, v.fov), width, height, x, y), kSunHandleMinElevation,
                      kSunHandleMaxElevation);
  sun_by_hand(v);
}

// A mouse button pressed or let go at (x, y): with Shift the sun drag, else orbit / look. What the
// GLFW callback and the window test's automation (CLOUDVIEWER_WINDOW_ACTIONS) both call.
void mouse_button(ViewState& v, bool pressed, int mods, double x, double y, int width, int height) {
  v.last_x = x, v.last_y = y;
  v.sun_drag = pressed && (mods & GLFW_MOD_SHIFT);
  v.dragging = pressed && !v.sun_drag;
  if (v.sun_drag) sun_to(v, x, y, width, height);
}

// The cursor moved to (x, y) with a button held: the sun follows it, or the camera turns.
void mouse_move(ViewState& v, double x, double y, int width, int height) {
  if (v.sun_drag) return sun_to(v, x, y, width, height);
  if (!v.dragging) return;
  double dx = x - v.last_x, dy = y - v.last_y;
  v.last_x = x, v.last_y = y;
  if (v.fly) {
    v.fly_yaw -= dx * 0.2;
    v.fly_pitch = std::clamp(v.fly_pitch - dy * 0.2, -89.0, 89.0);
  } else {
    v.yaw -= dx * 0.3;
    v.pitch = std::clamp(v.pitch + dy * 0.3, -89.0, 89.0);
  }
}

void on_key(GLFWwindow* w, int key, int, int action, int mods) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  auto* v = static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  if (v->panel && v->panel->visible && Panel::wants_keyboard()) return;  // typing into the panel
  // Camera bookmarks (Ctrl stores, Shift recalls) and Reset view, done in the frame loop.
  if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9 && (mods & (GLFW_MOD_CONTROL | GLFW_MOD_SHIFT))) {
    ((mods & GLFW_MOD_CONTROL) ? v->camera->store : v->camera->recall) = key - GLFW_KEY_1;
    return;
  }
  if (key == GLFW_KEY_HOME) {
    v->camera->reset = true;
    return;
  }
  if ((mods & GLFW_MOD_CONTROL) && v->file && v->file->preset) {  // the preset's file actions
    if (key == GLFW_KEY_S) v->file->save = true;
    if (key == GLFW_KEY_E) v->file->export_vdb = true;
    if (key == GLFW_KEY_B) v->file->blender = true;
    return;
  }
  RenderSettings& s = *v->settings;
  Sun& sun = *v->sun;
  if (key == GLFW_KEY_KP_ADD) key = GLFW_KEY_EQUAL;
  if (key == GLFW_KEY_KP_SUBTRACT) key = GLFW_KEY_MINUS;
  for (const KeyBinding& b : key_bindings())
    if (b.glfw_key == key) {
      apply_binding(s, b);
      return;
    }
  switch (key) {
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(w, 1); break;
    // The azimuth kept in [-180, 180] (the preset's view.sun.azimuth takes [-360, 360]).
    case GLFW_KEY_LEFT: sun.azimuth_deg = std::remainder(sun.azimuth_deg - 5, 360.0), sun_by_hand(*v); break;
    case GLFW_KEY_RIGHT: sun.azimuth_deg = std::remainder(sun.azimuth_deg + 5, 360.0), sun_by_hand(*v); break;
    case GLFW_KEY_UP:
      sun.elevation_deg = std::min(kSunHandleMaxElevation, sun.elevation_deg + 2.5), sun_by_hand(*v);
      break;
    case GLFW_KEY_DOWN:
      sun.elevation_deg = std::max(kSunHandleMinElevation, sun.elevation_deg - 2.5), sun_by_hand(*v);
      break;
    case GLFW_KEY_F: v->fly = !v->fly; break;
    case GLFW_KEY_R: v->reload_requested = true; break;
    case GLFW_KEY_F1:
      if (v->panel) v->panel->visible = !v->panel->visible;
      break;
    case GLFW_KEY_F12: v->save_requested = true; break;
    case GLFW_KEY_C: v->camera->reference = !v->camera->reference; break;
    case GLFW_KEY_SPACE: v->playing = !v->playing; break;
    case GLFW_KEY_COMMA: v->time_scale = std::max(1.0 / 64, v->time_scale / 2); break;
    case GLFW_KEY_PERIOD: v->time_scale = std::min(1024.0, v->time_scale * 2); break;
    case GLFW_KEY_BACKSPACE: s.time = v->start_time; break;
    case GLFW_KEY_H: *v->out << kWindowKeys << key_help_markdown(); break;
    default: break;
  }
}

void on_button(GLFWwindow* w, int button, int action, int mods) {
  auto* v = static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  if (action == GLFW_PRESS && v->panel && v->panel->visible && Panel::wants_mouse()) return;
  if (button == GLFW_MOUSE_BUTTON_LEFT || button == GLFW_MOUSE_BUTTON_RIGHT) {
    double x = 0, y = 0;
    int width = 0, height = 0;
    glfwGetCursorPos(w, &x, &y);
    glfwGetWindowSize(w, &width, &height);
    mouse_button(*v, action == GLFW_PRESS, mods, x, y, width, height);
  }
}

void on_cursor(GLFWwindow* w, double x, double y) {
  auto* v = static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  int width = 0, height = 0;
  glfwGetWindowSize(w, &width, &height);
  mouse_move(*v, x, y, width, height);
}

void on_scroll(GLFWwindow* w, double, double dy) {
  auto* v = static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  if (v->panel && v->panel->visible && Panel::wants_mouse()) return;
  if (v->fly) v->move_speed *= std::pow(1.2, dy);
  else v->distance *= std::pow(0.9, dy);
}

// GLFW for the window's lifetime.
struct Glfw {
  Glfw() {
    if (!glfwInit()) throw GlError("GLFW could not initialise (no display? use --headless, or run under xvfb-run)");
  }
  ~Glfw() { glfwTerminate(); }
};

// An OpenGL 4.5 core window, EGL first: libepoxy then finds the context through EGL, and the same
// driver stack serves the headless path; GLX as the fallback. Its context is made current.
struct Window {
  Window(int width, int height) {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_EGL_CONTEXT_API);
    w = glfwCreateWindow(width, height, "cloudviewer", nullptr, nullptr);
    if (!w) {
      glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_NATIVE_CONTEXT_API);
      w = glfwCreateWindow(width, height, "cloudviewer", nullptr, nullptr);
    }
    if (!w) throw GlError("could not open an OpenGL 4.5 core window");
    glfwMakeContextCurrent(w);
    glfwSwapInterval(0);
  }
  ~Window() { glfwDestroyWindow(w); }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* w = nullptr;
};

// The orbit camera around the start view's target, the fly camera at its eye.
void start_view(ViewState& view, const Camera& start, const PreparedVolume& vol) {
  view.pivot = start.target;
  glm::dvec3 d = start.target - start.eye;
  view.distance = glm::length(d);
  view.yaw = glm::degrees(std::atan2(d.x, d.z));
  view.pitch = -glm::degrees(std::asin(std::clamp(d.y / view.distance, -1.0, 1.0)));
  view.fly_eye = start.eye;
  view.fly_yaw = view.yaw;
  view.fly_pitch = -view.pitch;
  view.move_speed = std::max(10.0, glm::length(vol.size()) * 0.1);
}

// Fly mode: W A S D, Q E move the eye (Shift: five times as fast).
void fly(GLFWwindow* window, ViewState& view, double dt) {
  glm::dvec3 f = forward_of(view.fly_yaw, view.fly_pitch);
  glm::dvec3 r = glm::normalize(glm::cross(f, glm::dvec3(0, 1, 0)));
  double sp = view.move_speed * dt * (glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ? 5.0 : 1.0);
  auto down = [&](int key) { return glfwGetKey(window, key) == GLFW_PRESS; };
  if (down(GLFW_KEY_W)) view.fly_eye += f * sp;
  if (down(GLFW_KEY_S)) view.fly_eye -= f * sp;
  if (down(GLFW_KEY_D)) view.fly_eye += r * sp;
  if (down(GLFW_KEY_A)) view.fly_eye -= r * sp;
  if (down(GLFW_KEY_E)) view.fly_eye.y += sp;
  if (down(GLFW_KEY_Q)) view.fly_eye.y -= sp;
}

// The shader directory and the input file, watched: a change (or R) reloads them; a failed reload
// keeps what the window shows. The input is opened again on a worker thread (a preset generated
// from the noise kept since the last time, cloudgen::NoiseCache) while the window keeps drawing
// the old volume; collect() swaps it in on the GL thread when it is ready.
class Watcher {
 public:
  explicit Watcher(const Options& o)
      : o_(o), watch_input_(o.input.rfind("synthetic:", 0) != 0),
        input_time_(watch_input_ ? mtime_of(o.input) : fs::file_time_type{}), shader_times_(dir_times(o.shader_dir)) {}
  void poll(Session& session, const RenderSettings& settings, bool requested, std::ostream& out, std::ostream& err) {
    auto st = dir_times(o_.shader_dir);
    if (st != shader_times_ || (requested && !o_.shader_dir.empty())) {
      shader_times_ = st;
      try {
        session.renderer()->reload_shaders();
        out << "shaders reloaded from " << o_.shader_dir << "\n";
      } catch (const ShaderError& e) {
        err << e.what() << "(keeping the previous shaders)\n";
      }
    }
    if (watch_input_ && (mtime_of(o_.input) != input_time_ || requested)) {
      input_time_ = mtime_of(o_.input);
      pending_ = true;  // a change during a reload starts another after it
    }
    if (pending_ && !job_.valid()) start(session, settings);
  }

  /// An edit of the preset (the panel): regenerate now, or as soon as the reload in flight ends.
  void request(const Session& session, const RenderSettings& settings) {
    pending_ = true;
    if (!job_.valid()) start(session, settings);
  }

  /// No reload in flight or waiting.
  bool idle() const { return !pending_ && !job_.valid(); }
  /// A finished reload waits: the next collect replaces the volume.
  bool ready() const { return job_.valid() && job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready; }

  /// Every frame: a finished reload replaces the volume (the upload happens here, on the GL thread).
  void collect(Session& session, std::ostream& out, std::ostream& err) {
    if (!job_.valid() || job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    try {
      session.adopt(job_.get());
      out << "reloaded " << o_.input << " in "
          << std::lround(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started_).count())
          << " ms\n";
    } catch (const Error& e) {
      err << "reload failed: " << e.what() << " (keeping the previous volume)\n";
    }
  }

 private:
  void start(const Session& session, const RenderSettings& settings) {
    pending_ = false;
    started_ = std::chrono::steady_clock::now();
    // The session's noise cache goes with it: one reload at a time uses it.
    job_ = std::async(std::launch::async, [input = o_.input, settings, level = session.lod_level(), preset = session.preset()] {
      return open_input(input, settings, level, preset);
    });
  }

  const Options& o_;
  bool watch_input_;
  fs::file_time_type input_time_;
  std::map<std::string, fs::file_time_type> shader_times_;
  bool pending_ = false;
  std::chrono::steady_clock::time_point started_;
  std::future<PreparedVolume> job_;  // (its destructor waits for a reload in flight)
};

// The panel's file actions on a preset INPUT: Save preset as at once (a small JSON file), Export
// and Open in Blender on a worker thread, one at a time, while the window keeps drawing.
class FileActions {
 public:
  FileActions(const Options& o, PanelFile& f) : f_(f) {
    std::string ext = fs::path(o.input).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    f.preset = ext == ".json";
#endif
    f.save_path = edited_name(o.input, ".json");
    f.export_path = edited_name(o.input, ".vdb");
  }
  /// Every frame, on the GL thread: the panel's preset edits, checked and added to the session's;
  /// true when one changes the volume (the caller regenerates it on the watcher's worker).
  bool edit(Session& session) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    if (f_.preset && f_.values.empty()) f_.values = cloudgen::preset_values(session.input(), session.preset().sets);
#endif
    if (f_.edits.empty()) return false;
    bool applied = false, regenerate = false;
    for (const std::string& e : f_.edits) {
      try {
        session.edit_preset(e);
        applied = true;
        // The view, the export options and the names go with Save as and Export; the volume stays.
        bool volume = true;
        for (const char* kept : {"view.", "export.", "name=", "description="}) volume = volume && e.rfind(kept, 0) != 0;
        regenerate = regenerate || volume;
        f_.edit_status = volume ? "" : "kept for Save preset as and Export: " + e;
      } catch (const Error& x) {
        f_.edit_status = x.what();
      }
    }
    f_.edits.clear();
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
    if (applied) f_.values = cloudgen::preset_values(session.input(), session.preset().sets);
#endif
    return regenerate;
  }

  /// Every frame, on the GL thread: starts what the panel or the keys asked for, collects a finished job.
  void run(const Session& session, std::ostream& out) {
    if (f_.save) {
      f_.save = false;
      try {
        session.save_preset_as(f_.save_path);
        f_.status = "saved " + cloudgen::printable(f_.save_path) + " (" + std::to_string(session.preset().sets.size()) +
                    " edits)";
      } catch (const std::exception& e) {
        f_.status = std::string("not saved: ") + e.what();
      }
      out << f_.status << "\n";
    }
    if ((f_.export_vdb || f_.blender) && !job_.valid()) {
      const bool blender = f_.blender;
      f_.export_vdb = f_.blender = false;
      f_.busy = true;
      f_.progress = blender ? -1.f : 0.f;
      progress_ = 0;
      f_.status = blender ? "making the Blender scene..." : "exporting " + cloudgen::printable(f_.export_path) + "...";
      const std::string vdb = f_.export_path, blend = fs::path(vdb).replace_extension(".blend").string();
      job_ = std::async(std::launch::async, [this, blender, vdb, blend, input = session.input(), sets = session.preset().sets] {
        if (blender) {
          std::error_code ec;
          if (!fs::is_regular_file(vdb, ec)) throw InputError("no " + vdb + " yet: Export first (Ctrl+E)");
          return "Blender scene " + open_in_blender(vdb, blend);
        }
        export_preset_files(input, sets, {vdb}, [this](double x) { progress_ = float(x); });
        return "exported " + vdb;
      });
    }
    f_.export_vdb = f_.blender = false;  // asked while busy: ignored
    if (job_.valid()) {
      f_.progress = f_.progress < 0 ? -1.f : progress_.load();
      if (job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
        try {
          f_.status = job_.get();
        } catch (const std::exception& e) {
          f_.status = std::string("failed: ") + e.what();
        }
        f_.busy = false;
        out << f_.status << "\n";
      }
    }
  }

 private:
  PanelFile& f_;
  std::atomic<float> progress_{0};
  std::future<std::string> job_;  // (its destructor waits for a job in flight)
};

// A file action asked for or in flight.
bool automating_action(const PanelFile& f) { return f.busy || f.save || f.export_vdb || f.blender; }

std::string panel_hint(const ViewState& view, const RenderSettings& settings, const Sun& sun) {
  std::ostringstream hint;
  hint.precision(3);
  hint << "sun " << sun.azimuth_deg << ", " << sun.elevation_deg << (view.fly ? " | fly" : " | orbit") << " | t "
       << settings.time << " s" << (view.playing ? " x" + format_scale(view.time_scale) : " paused")
       << " | H keys, F1 hide\nShift+drag: sun | Home: reset view";
  return hint.str();
}

std::string window_title(const ViewState& view, const RenderSettings& settings, const Sun& sun, double gpu_ms,
                         double cloud_ms) {
  std::ostringstream title;
  title.precision(3);
  title << "cloudviewer | GPU " << gpu_ms << " ms (clouds " << cloud_ms << ") | steps " << settings.steps
        << " occ:" << (settings.occupancy ? "on" : "off") << " adapt:" << (settings.adaptive ? "on" : "off")
        << " light:" << (settings.light_march ? "on" : "off") << " phase:" << value_of(settings, "phase")
        << " g:" << settings.g << " tone:" << value_of(settings, "tonemap") << " bloom:" << settings.bloom
        << " density:" << settings.density << " exp:" << settings.exposure << " | sun " << sun.azimuth_deg << ","
        << sun.elevation_deg << (view.fly ? " | fly" : " | orbit") << " | t " << settings.time << " s"
        << (view.playing ? "" : " paused");
  return title.str();
}

// F12 (cloudviewer_N.png and .exr), or with --out the last automatic frame (then the window closes).
void save_frame(const Options& o, GLFWwindow* window, GlRenderer& renderer, bool auto_save, int frame, int& saved,
                const GpuTimings& t, std::ostream& out) {
  FrameImages img = renderer.read_back();
  std::string base = auto_save ? o.out : "cloudviewer_" + std::to_string(saved++);
  if (auto_save) {
    write_image(o.out, img.display, img.linear);
    out << "wrote " << cloudgen::printable(o.out) << " (frame " << frame << ", GPU " << t.total_ms << " ms)\n";
    glfwSetWindowShouldClose(window, 1);
  } else {
    write_png(base + ".png", img.display);
    write_exr(base + ".exr", img.linear);
    out << "saved " << base << ".png and " << base << ".exr\n";
  }
}

// A double as text that reads back as the same double.
std::string exact(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The camera requests of the keys and the panel: Reset view, store and recall a bookmark.
void camera_requests(ViewState& v, std::ostream& out) {
  PanelCamera& c = *v.camera;
  CameraPose& pose = v;
  if (c.reset) {
    pose = v.home;
    out << "view reset to the preset's view\n";
  }
  if (c.store >= 0 && c.store < int(v.bookmarks.size())) {
    v.bookmarks[size_t(c.store)] = pose;
    out << "camera stored in bookmark " << c.store + 1 << "\n";
  }
  if (c.recall >= 0 && c.recall < int(v.bookmarks.size()) && v.bookmarks[size_t(c.recall)]) {
    pose = *v.bookmarks[size_t(c.recall)];
    out << "camera from bookmark " << c.recall + 1 << "\n";
  }
  c.reset = false;
  c.store = c.recall = -1;
  for (size_t i = 0; i < v.bookmarks.size(); ++i) c.stored[i] = v.bookmarks[i].has_value();
}

// The preset's view.sun as the panel shows it (`seen`, "AZ,EL" as JSON text): an edit of it on the
// panel moves the window's sun. The first values are the start's, which --sun or
// render.time_of_day may have overridden.
void follow_view_sun(const PanelFile& f, Sun& sun, std::string& seen) {
  const auto az = f.values.find("view.sun.azimuth"), el = f.values.find("view.sun.elevation");
  if (az == f.values.end() || el == f.values.end()) return;
  const std::string now = az->second + "," + el->second;
  if (seen.empty() || now == seen) {
    seen = now;
    return;
  }
  seen = now;
  auto number = [](const std::string& text, double& out) {
    char* end = nullptr;
    const double d = std::strtod(text.c_str(), &end);
    if (end != text.c_str() && *end == '\0' && std::isfinite(d)) out = d;
  };
  number(az->second, sun.azimuth_deg);
  number(el->second, sun.elevation_deg);
}

// The reference in the window (issue 42 item 3): the path tracer's image of the frame the window
// would draw, refined pass by pass (kPassPaths paths per pixel each, the next paths of every
// pixel's stream, so n passes trace what `--backend pathtrace --spp n*kPassPaths` traces) on a
// worker thread while the window keeps answering, and shown in place of the real-time frame. A
// change of the view, the sun, a setting or the volume starts it again.
class Reference {
 public:
  static constexpr int kPassPaths = 1;
  ~Reference() { stop(); }
  /// Ends the pass in flight (within a row of pixels) and forgets the image.
  void stop() {
    if (job_.valid()) {
      cancel_ = true;
      job_.wait();
      job_ = {};
      cancel_ = false;
    }
    sum_ = PathTraceSum{};
    shown_ = Image();
    shown_paths_ = 0;
    key_.clear();
  }
  /// Each frame while on, before anything can change the volume: `key` names what the frame will
  /// show; a new one ends the pass in flight and starts again.
  void follow(const std::string& key) {
    if (key != key_) {
      stop();
      key_ = key;
    }
  }
  /// Then: collects a finished pass and starts the next (up to `max_paths` per pixel). Returns the
  /// image to show, or null before the first pass is done.
  const Image* update(const Session& session, const FrameSetup& frame, long long max_paths) {
    if (job_.valid() && job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      FrameImages img = job_.get();
      if (img.display.width > 0) shown_ = std::move(img.display), shown_paths_ = sum_.paths;
    }
    if (!job_.valid() && sum_.paths < max_paths) {
      PathTraceOptions o;
      o.spp = kPassPaths;
      o.first_sample = int(sum_.paths);
      o.sum = &sum_;
      o.cancel = &cancel_;
      job_ = std::async(std::launch::async, [&vol = session.volume(), frame, o] { return render_pathtrace(vol, frame, o); });
    }
    return shown_.width > 0 ? &shown_ : nullptr;
  }
  /// Paths per pixel in the image shown (0: none yet).
  long long paths() const { return shown_paths_; }

 private:
  std::future<FrameImages> job_;
  std::atomic<bool> cancel_{false};
  PathTraceSum sum_;  // the worker's while a pass runs
  Image shown_;
  long long shown_paths_ = 0;
  std::string key_;
};

// One step of CLOUDVIEWER_WINDOW_ACTIONS (tests/window_handles.sh) on the window's own input paths:
// "sundrag:X0,Y0,X1,Y1" a Shift + drag from one window point to another (fractions of the window's
// size), "orbit:DX,DY" a plain drag by DX, DY pixels from the centre, "reset", "store:N",
// "recall:N", "set:KEY=VALUE" a render.* key as the panel sets it, "reference" the C key, "panel"
// the F1 key. False: not one of these.
bool handle_action(const std::string& a, ViewState& v, GLFWwindow* window, RenderSettings& s) {
  int w = 0, h = 0;
  glfwGetWindowSize(window, &w, &h);
  const size_t colon = a.find(':');
  const std::string verb = a.substr(0, colon), arg = colon == std::string::npos ? "" : a.substr(colon + 1);
  std::vector<double> n;
  for (std::istringstream in(arg); in.good();) {
    double d = 0;
    char comma = 0;
    if (in >> d) n.push_back(d);
    in >> comma;
  }
  if (verb == "sundrag" && n.size() == 4) {
    mouse_button(v, true, GLFW_MOD_SHIFT, n[0] * w, n[1] * h, w, h);
    for (int i = 1; i <= 4; ++i)
      mouse_move(v, (n[0] + (n[2] - n[0]) * i / 4) * w, (n[1] + (n[3] - n[1]) * i / 4) * h, w, h);
    mouse_button(v, false, GLFW_MOD_SHIFT, n[2] * w, n[3] * h, w, h);
  } else if (verb == "orbit" && n.size() == 2) {
    mouse_button(v, true, 0, w / 2.0, h / 2.0, w, h);
    mouse_move(v, w / 2.0 + n[0], h / 2.0 + n[1], w, h);
    mouse_button(v, false, 0, w / 2.0 + n[0], h / 2.0 + n[1], w, h);
  } else if (verb == "reset") {
    v.camera->reset = true;
  } else if (verb == "reference") {
    v.camera->reference = !v.camera->reference;
  } else if (verb == "panel") {
    if (v.panel) v.panel->visible = !v.panel->visible;
  } else if ((verb == "store" || verb == "recall") && n.size() == 1) {
    (verb == "store" ? v.camera->store : v.camera->recall) = int(n[0]) - 1;
  } else if (verb == "set" && !arg.empty()) {
    apply_setting(s, arg);
  } else {
    return false;
  }
  return true;
}

}  // namespace

int run_window(const Options& opts, std::ostream& out, std::ostream& err) {
  Options o = opts;
  const uint32_t level = choose_input_lod(o, out);  // at the window's size and starting camera
  RenderSettings settings = o.settings;
  RenderSettings good_settings = settings;  // the last settings a frame took (make_frame_or_keep)
  PresetSource preset{o.preset_sets, nullptr};
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  cloudgen::NoiseCache noise;  // a reload of an edited preset recombines the kept noise (outlives the Watcher)
  preset.noise_cache = &noise;
#endif
  Session session(o.input, settings, level, preset);  // load first, so a bad input fails before a window opens
  Glfw glfw;
  Window win(o.width, o.height);
  GLFWwindow* window = win.w;
  struct StopRenderer {  // the renderer goes before the window (GL objects need the context)
    Session& s;
    ~StopRenderer() { s.stop_renderer(); }
  } stop_renderer{session};

  Camera start = resolve_camera(o, session.volume(), o.width, o.height);
  Sun sun = resolve_sun(o, start);
  ViewState view;
  view.settings = &settings;
  view.sun = &sun;
  view.start_time = settings.time;
  view.out = &out;
  view.fov = o.fov;
  start_view(view, start, session.volume());
  view.home = view;  // the pose alone: Reset view's
  PanelCamera camera_panel;
  view.camera = &camera_panel;
  glfwSetWindowUserPointer(window, &view);
  glfwSetKeyCallback(window, on_key);
  glfwSetMouseButtonCallback(window, on_button);
  glfwSetCursorPosCallback(window, on_cursor);
  glfwSetScrollCallback(window, on_scroll);

  GlRenderer& renderer = session.start_renderer(o.shader_dir);
  // After our callbacks: ImGui chains to them.
  Panel panel(window);
  panel.help = std::string(kWindowKeys) + key_help_markdown();
  view.panel = &panel;
  PanelFile file;
  FileActions actions(o, file);
  view.file = &file;
  out << "window: " << renderer.renderer_string() << " (press H for keys, F1 for the panel)\n";

  Watcher watcher(o);
  Reference reference;  // after the session: its passes read the session's volume
  // The reference's paths per pixel: --spp (64 unless given), then it rests.
  const long long reference_paths = std::max(1, o.spp);
  auto last_poll = std::chrono::steady_clock::now();
  auto last_frame = last_poll;
  int frame = 0, saved = 0;
  double gpu_ms_avg = 0, cloud_ms_avg = 0;
  // With --out: render a few frames, save, exit. --edit (a preset) goes through the panel's own
  // edit path after the first frame; the frames count from 0 again once its regeneration is shown,
  // so the saved frame is the one a fresh --set of the same keys saves.
  const int auto_frames = o.out.empty() ? 0 : 3;
  bool edits_sent = false, edits_waiting = false;
  // CLOUDVIEWER_WINDOW_ACTIONS="save export blender" (with --out; tests/window_edit.sh): the panel's
  // file actions, one after another once the edits are shown, as the buttons ask for them.
  std::vector<std::string> todo;
  if (const char* a = std::getenv("CLOUDVIEWER_WINDOW_ACTIONS"); a && auto_frames > 0) {
    std::istringstream words(a);
    for (std::string w; words >> w;) todo.push_back(w);
  }
  auto automating = [&] {
    return edits_waiting || !todo.empty() || automating_action(file) ||
           (camera_panel.reference && reference.paths() < reference_paths);
  };
  bool was_automating = false;
  // render.time_of_day, render.latitude and render.day_of_year as the last frame had them: a change
  // (the panel's sliders) puts the sun on the day's path.
  auto sun_clock = [&] { return std::make_tuple(settings.time_of_day, settings.latitude, settings.day_of_year); };
  auto last_clock = sun_clock();
  std::string seen_view_sun;  // follow_view_sun's
  while (!glfwWindowShouldClose(window)) {
    glfwPollEvents();
    auto now = std::chrono::steady_clock::now();
    double dt = std::chrono::duration<double>(now - last_frame).count();
    last_frame = now;
    if (view.playing && auto_frames == 0) settings.time += dt * view.time_scale;
    if (view.fly) fly(window, view, dt);
    // Poll the preset and the shader directory ten times a second (a few stat calls): a saved edit
    // waits at most 100 ms before its regeneration starts.
    if (now - last_poll > std::chrono::milliseconds(100) || view.reload_requested) {
      last_poll = now;
      watcher.poll(session, settings, view.reload_requested, out, err);
      view.reload_requested = false;
    }
    if (auto_frames > 0 && frame == 1 && !o.edits.empty() && !edits_sent) {
      file.edits = o.edits;
      edits_sent = edits_waiting = true;
    }
    if (!edits_waiting && frame >= 1 && !todo.empty() && !automating_action(file)) {
      const std::string a = todo.front();
      todo.erase(todo.begin());
      if (a == "save" || a == "export" || a == "blender") {
        (a == "save" ? file.save : a == "export" ? file.export_vdb : file.blender) = true;
      } else {
        try {
          if (!handle_action(a, view, window, settings)) err << "CLOUDVIEWER_WINDOW_ACTIONS: unknown action " << a << "\n";
        } catch (const InputError& e) {
          err << "CLOUDVIEWER_WINDOW_ACTIONS: " << e.what() << "\n";
        }
      }
    }
    camera_requests(view, out);
    if (sun_clock() != last_clock) {
      last_clock = sun_clock();
      if (settings.time_of_day >= 0) {
        sun = solar_sun(settings.latitude, settings.day_of_year, settings.time_of_day);
        view.sun_moved = true;
      }
    }
    // A sun the handles moved is kept as the preset's view.sun (Save as writes it) once the mouse
    // lets go: one edit per drag, not one per frame.
    if (view.sun_moved && !view.sun_drag && glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) != GLFW_PRESS) {
      view.sun_moved = false;
      out << "sun " << exact(sun.azimuth_deg) << "," << exact(sun.elevation_deg) << " (azimuth, elevation)\n";
      if (file.preset) {
        file.edits.push_back("view.sun.azimuth=" + exact(sun.azimuth_deg));
        file.edits.push_back("view.sun.elevation=" + exact(sun.elevation_deg));
      }
    }
    if (actions.edit(session)) watcher.request(session, settings);
    if (file.preset) follow_view_sun(file, sun, seen_view_sun);
    if (watcher.ready()) reference.stop();  // the volume it reads is about to be replaced
    watcher.collect(session, out, err);
    if (edits_waiting && watcher.idle()) edits_waiting = false;
    if (was_automating && !automating()) frame = 0;  // the saved frame is then a fresh run's frame
    was_automating = automating();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    if (fw < 1 || fh < 1) continue;
    settings.frame = frame;
    Camera cam = camera_of(view, o.fov);
    // The reference follows what this frame shows (its pass in flight ends before fit can change the
    // volume's field): the settings (the clock only while clouds move), the camera, the sun, the
    // volume and the size.
    if (camera_panel.reference) {
      RenderSettings k = settings;
      k.frame = 0;
      if (session.volume().baked_motion || !cloudgen::motion_moves(k.motion)) k.time = 0;
      std::ostringstream key;
      key.precision(17);
      key << describe_settings(k) << cam.eye.x << ',' << cam.eye.y << ',' << cam.eye.z << ';' << cam.target.x << ','
          << cam.target.y << ',' << cam.target.z << ';' << cam.fov_y_deg << ';' << sun.azimuth_deg << ',' << sun.elevation_deg
          << ';' << static_cast<const void*>(session.volume().rgba.data()) << ';' << fw << 'x' << fh;
      reference.follow(key.str());
    } else {
      reference.stop();
    }
    // The panel and the keys change the erosion and the motion: the field follows (a few ms on the
    // thesis volume; exact meanwhile, since make_frame never trusts a field that does not cover).
    session.fit(settings);
    // A panel choice this volume refuses goes back, with the reason, instead of ending the window.
    std::string refused;
    FrameSetup fs = session.frame_or_keep(settings, good_settings, cam, sun, fw, fh, refused);
    if (!refused.empty()) err << refused << " (the panel's choice is undone)\n";
    GpuTimings t;
    const Image* truth = camera_panel.reference ? reference.update(session, fs, reference_paths) : nullptr;
    camera_panel.reference_paths = reference.paths();
    if (truth) {
      renderer.present_image(*truth, fw, fh);  // the real-time frame is not drawn meanwhile
    } else {
      renderer.render(fs, &t);
      renderer.present(fw, fh);
    }
    panel.draw(settings, t, panel_hint(view, settings, sun), &file, &camera_panel);
    actions.run(session, out);
    if (auto_frames > 0 && !was_automating && !automating() && frame + 1 == auto_frames) {  // what the window shows, read from its back buffer before the swap
      std::string shot = fs::path(o.out).replace_extension("").string() + ".window.png";
      write_png(shot, renderer.read_window(fw, fh));
      out << "wrote " << cloudgen::printable(shot) << " (window back buffer " << fw << "x" << fh << ")\n";
    }
    glfwSwapBuffers(window);
    gpu_ms_avg = frame == 0 ? t.total_ms : gpu_ms_avg * 0.9 + t.total_ms * 0.1;
    cloud_ms_avg = frame == 0 ? t.cloud_ms : cloud_ms_avg * 0.9 + t.cloud_ms * 0.1;
    ++frame;
    if (frame % 4 == 1) glfwSetWindowTitle(window, window_title(view, settings, sun, gpu_ms_avg, cloud_ms_avg).c_str());
    const bool auto_save = auto_frames > 0 && !was_automating && !automating() && frame == auto_frames;
    if (view.save_requested || auto_save) {
      view.save_requested = false;
      save_frame(o, window, renderer, auto_save, frame, saved, t, out);
    }
  }
  return 0;
}

}  // namespace cloudviewer
