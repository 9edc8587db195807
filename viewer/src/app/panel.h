// The window's on-screen panel (Dear ImGui): one control per render.* key, built from the
// parameter table by panel_widgets() (settings.h), plus the GPU time of every pass. Internal.
#pragma once
#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cloudviewer/controls.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/settings.h"

struct GLFWwindow;

namespace cloudviewer {

/// The panel's file actions on a preset INPUT (Save preset as, Export, Open in Blender): the
/// panel edits the paths and sets a request; window.cpp does the work (authoring.h, Session) and
/// reports back in `status` and `progress`.
struct PanelFile {
  bool preset = false;  ///< the INPUT is a preset .json: the actions are offered
  std::string save_path, export_path, blend_path;
  bool save = false, export_vdb = false, blender = false;  ///< asked for this frame (buttons, Ctrl+S/E/B)
  bool busy = false;       ///< an export or a Blender scene is being made
  float progress = -1;     ///< the export's generation, [0, 1], while busy
  std::string status;      ///< the last action's outcome (the .blend's path, an error)
  /// The preset's fields (cloudgen::preset_values: KEY -> JSON text), drawn in their groups.
  std::map<std::string, std::string> values;
  std::vector<std::string> edits;  ///< KEY=VALUE the user asked for this frame (Session::edit_preset)
  std::string edit_status;         ///< the last refused edit's reason
};

/// The window's camera handles on the panel: Reset view (the preset's `view`) and the session's
/// bookmarks 1-9. The panel and the keys (Home, Ctrl+N, Shift+N) ask; window.cpp moves the camera.
struct PanelCamera {
  bool reset = false;            ///< asked for this frame
  int store = -1, recall = -1;   ///< a bookmark (0..8) asked for this frame
  std::array<bool, 9> stored{};  ///< which bookmarks hold a camera
  /// The path tracer's progressive image in place of the frame (C, or the panel's checkbox), and
  /// how many paths per pixel it holds so far.
  bool reference = false;
  long long reference_paths = 0;
};

class Panel {
 public:
  /// Installs ImGui's GLFW callbacks, chaining to the ones already set on the window.
  explicit Panel(GLFWwindow* window);
  ~Panel();
  Panel(const Panel&) = delete;
  Panel& operator=(const Panel&) = delete;
  /// Builds and draws the panel into the current framebuffer (after the frame's present()).
  /// Changes `s` where the user moved a control; `hint` is a line shown under the title.
  /// `file`: the file actions of a preset INPUT (null: none); `camera`: Reset view and the
  /// bookmarks (null: not shown).
  void draw(RenderSettings& s, const GpuTimings& t, const std::string& hint, PanelFile* file = nullptr,
            PanelCamera* camera = nullptr);
  /// True while ImGui uses the keyboard or mouse (the window's own bindings then stay quiet).
  static bool wants_keyboard();
  static bool wants_mouse();
  bool visible = true;
  /// The window's key list (Markdown table rows, as H prints it), shown under "Keys".
  std::string help;

 private:
  double last_lut_ms_ = 0;  ///< GPU time of the last atmosphere LUT recompute
};

}  // namespace cloudviewer
