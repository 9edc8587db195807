// The window's on-screen panel (Dear ImGui): one control per render.* key, built from the
// parameter table by panel_widgets() (settings.h), plus the GPU time of every pass. Internal.
#pragma once
#include <memory>

#include "cloudviewer/controls.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/settings.h"

struct GLFWwindow;

namespace cloudviewer {

class Panel {
 public:
  /// Installs ImGui's GLFW callbacks, chaining to the ones already set on the window.
  explicit Panel(GLFWwindow* window);
  ~Panel();
  Panel(const Panel&) = delete;
  Panel& operator=(const Panel&) = delete;
  /// Builds and draws the panel into the current framebuffer (after the frame's present()).
  /// Changes `s` where the user moved a control; `hint` is a line shown under the title.
  void draw(RenderSettings& s, const GpuTimings& t, const std::string& hint);
  /// True while ImGui uses the keyboard or mouse (the window's own bindings then stay quiet).
  static bool wants_keyboard();
  static bool wants_mouse();
  bool visible = true;

 private:
  double last_lut_ms_ = 0;  ///< GPU time of the last atmosphere LUT recompute
};

}  // namespace cloudviewer
