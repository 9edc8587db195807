// The window's controls over the render parameters, built from their table (settings.h): key
// bindings and the panel's widgets.
#pragma once
#include <string>
#include <vector>

#include "cloudviewer/settings.h"

namespace cloudviewer {

/// A window key that changes a render parameter, declared by parameter and action; limits and
/// defaults come from the parameter table.
struct KeyBinding {
  enum class Action { Toggle, Cycle, Scale, Add, OnOff };
  std::string keys;    ///< as shown in the help ("[", "+ / -")
  int glfw_key = 0;    ///< GLFW_KEY_* code
  std::string param;   ///< render.KEY (without "render.")
  Action action = Action::Toggle;
  double amount = 0;   ///< Scale: factor; Add: increment
};
/// Every parameter key binding of the window (the camera, sun and file keys are in window.cpp).
const std::vector<KeyBinding>& key_bindings();
/// Applies a binding: toggles, cycles, or scales/adds clamped to the parameter's range, rounding
/// integers; OnOff switches a number between 0 and its table default.
void apply_binding(RenderSettings& s, const KeyBinding& b);
/// The key help (the H key and docs/reference/viewer-params.md), generated from the bindings and the table.
std::string key_help_markdown();

/// One control of the on-screen panel, built from the parameter table: what panel.cpp draws with
/// Dear ImGui for each render.* key (slider, checkbox, list) with its range, default and tooltip.
struct PanelWidget {
  enum class Kind { Checkbox, SliderInt, SliderFloat, Combo, SliderFloatOrAuto };
  std::string key;
  Kind kind = Kind::SliderFloat;
  double lo = 0, hi = 0;
  bool logarithmic = false;           ///< ranges spanning more than three decades
  std::vector<std::string> choices;
  std::string default_value, tooltip;
  cloudgen::ParamGroup group = cloudgen::ParamGroup::Unset;  ///< the table's group
  bool advanced = false;                                      ///< under the group's Advanced fold
};
/// The widgets the panel builds, one per parameter, in table order.
std::vector<PanelWidget> panel_widgets();

/// One collapsible group of the panel (cloudgen/param_group.h), the layout panel.cpp draws: its
/// render.* widgets and atmosphere.* keys, each split into the everyday ones and the engineering
/// switches under an "Advanced" fold, in table order.
struct PanelGroup {
  cloudgen::ParamGroup group = cloudgen::ParamGroup::Unset;
  std::string name;
  std::vector<PanelWidget> render, render_advanced;
  std::vector<std::string> atmosphere, atmosphere_advanced;  ///< keys without "atmosphere."
};
/// The panel's groups in kParamGroups order, the empty ones left out: every key of the render and
/// atmosphere tables in exactly one.
std::vector<PanelGroup> panel_groups();

}  // namespace cloudviewer
