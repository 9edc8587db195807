// Dear ImGui panel: every entry of the render and atmosphere parameter tables as a slider, checkbox
// or list with its range and default, the table's doc line as the tooltip, and per-pass GPU times.
// The layout comes from panel_groups(): one collapsible header per group of the tables (Shape,
// Detail, Light and sky, ...), the engineering switches under an Advanced fold in each, so a key
// added to a table appears here, in its group, with no code of its own. Follows imgui's examples/example_glfw_opengl3/main.cpp.
#include "app/panel.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "cloudviewer/controls.h"
#include "cloudviewer/errors.h"

namespace cloudviewer {

Panel::Panel(GLFWwindow* window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's folder
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.92f;
  if (!ImGui_ImplGlfw_InitForOpenGL(window, true) || !ImGui_ImplOpenGL3_Init("#version 450 core")) {
    ImGui::DestroyContext();
    throw GlError("Dear ImGui could not initialise its GLFW/OpenGL 3 backends");
  }
}

Panel::~Panel() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

bool Panel::wants_keyboard() { return ImGui::GetIO().WantCaptureKeyboard; }
bool Panel::wants_mouse() { return ImGui::GetIO().WantCaptureMouse; }

namespace {

void tooltip(const PanelWidget& w) {
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", w.tooltip.c_str());
}

// Applies a value through the table's own parser (ranges and messages stay the table's).
void set(RenderSettings& s, const std::string& key, const std::string& value) {
  try {
    render_param(key).set(s, value);
  } catch (const InputError&) {
    // A slider cannot leave the range; a typed value outside it is ignored.
  }
}

std::string text(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// One render.* control: slider, checkbox, list or auto + slider, with its tooltip.
void render_widget(RenderSettings& s, const PanelWidget& w) {
  const ParamDef& p = render_param(w.key);
  const std::string value = p.get(s);
  const char* label = w.key.c_str();
  const ImGuiSliderFlags flags = w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0;
  switch (w.kind) {
    case PanelWidget::Kind::Checkbox: {
      bool b = value == "true";
      if (ImGui::Checkbox(label, &b)) set(s, w.key, b ? "true" : "false");
      break;
    }
    case PanelWidget::Kind::SliderInt: {
      int v = std::stoi(value);
      if (ImGui::SliderInt(label, &v, int(w.lo), int(w.hi), "%d", flags)) set(s, w.key, std::to_string(v));
      break;
    }
    case PanelWidget::Kind::SliderFloat: {
      float v = std::stof(value);
      if (ImGui::SliderFloat(label, &v, float(w.lo), float(w.hi), "%.4g", flags)) set(s, w.key, text(v));
      break;
    }
    case PanelWidget::Kind::Combo: {
      int index = 0;
      for (size_t i = 0; i < w.choices.size(); ++i)
        if (w.choices[i] == value) index = int(i);
      std::vector<const char*> items;
      for (const std::string& c : w.choices) items.push_back(c.c_str());
      if (ImGui::Combo(label, &index, items.data(), int(items.size()))) set(s, w.key, w.choices[size_t(index)]);
      break;
    }
    case PanelWidget::Kind::SliderFloatOrAuto: {
      bool automatic = value == "auto";
      std::string auto_label = "auto##" + w.key;
      if (ImGui::Checkbox(auto_label.c_str(), &automatic)) set(s, w.key, automatic ? "auto" : "0");
      tooltip(w);
      ImGui::SameLine();
      float v = automatic ? 0.f : std::stof(value);
      ImGui::BeginDisabled(automatic);
      if (ImGui::SliderFloat(label, &v, float(w.lo), float(w.hi), "%.4g", flags)) set(s, w.key, text(v));
      ImGui::EndDisabled();
      break;
    }
  }
  tooltip(w);
}

// One atmosphere.* control: a change re-runs the LUT passes on the next frame.
void atmosphere_widget(RenderSettings& s, const std::string& key) {
  const AtmosphereParamDef* found = nullptr;
  for (const AtmosphereParamDef& p : atmosphere_params())
    if (p.key == key) found = &p;
  if (!found) return;
  const AtmosphereParamDef& p = *found;
  AtmosphereSettings defaults;
  const std::string value = p.get(s.atmosphere), label = "atmosphere." + p.key;
  const std::string tip = p.doc + " (" + p.type + ", " + p.range + ", default " + p.get(defaults) + ")";
  AtmosphereSettings next = s.atmosphere;
  bool changed = false;
  try {
    if (p.type == "bool") {
      bool b = value == "true";
      if (ImGui::Checkbox(label.c_str(), &b)) p.set(next, b ? "true" : "false"), changed = true;
    } else if (p.type == "int") {
      int v = std::stoi(value);
      if (ImGui::SliderInt(label.c_str(), &v, int(p.lo), int(p.hi))) p.set(next, std::to_string(v)), changed = true;
    } else {
      float v = std::stof(value);
      const bool log_scale = p.lo >= 0 && p.hi / std::max(p.lo, 1e-12) > 1e3;
      // Per-metre coefficients are ~1e-6: the slider shows them in those units' own exponent.
      if (ImGui::SliderFloat(label.c_str(), &v, float(p.lo), float(p.hi), "%.4g",
                             log_scale ? ImGuiSliderFlags_Logarithmic : 0))
        p.set(next, text(v)), changed = true;
    }
    if (changed) {
      validate_atmosphere(next);  // e.g. top above bottom; an invalid combination is not applied
      s.atmosphere = next;
    }
  } catch (const InputError&) {
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tip.c_str());
}

// A path field over a std::string.
void path_field(const char* label, std::string& path) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, "%s", path.c_str());
  if (ImGui::InputText(label, buf, sizeof buf)) path = buf;
}

// Save preset as, Export and Open in Blender, with their paths, progress and outcome.
void file_actions(PanelFile& f) {
  if (!ImGui::CollapsingHeader("Preset file", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::PushItemWidth(200);
  path_field("##save", f.save_path);
  ImGui::SameLine();
  if (ImGui::Button("Save preset as")) f.save = true;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Ctrl+S: the preset with the panel's edits, as JSON (atomic; never into presets/)");
  path_field("##export", f.export_path);
  ImGui::SameLine();
  ImGui::BeginDisabled(f.busy);
  if (ImGui::Button("Export")) f.export_vdb = true;
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("Ctrl+E: generate and write the VDB as `cloudgen generate` does");
  if (ImGui::Button("Open in Blender")) f.blender = true;
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("Ctrl+B: `cloudgen blender` of the exported VDB");
  ImGui::EndDisabled();
  ImGui::PopItemWidth();
  if (f.busy && f.progress >= 0) ImGui::ProgressBar(f.progress, ImVec2(-1, 0));
  if (!f.status.empty()) ImGui::TextWrapped("%s", f.status.c_str());
}

}  // namespace

void Panel::draw(RenderSettings& s, const GpuTimings& t, const std::string& hint, PanelFile* file) {
  if (!visible) return;
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("cloudviewer");
  ImGui::TextUnformatted(hint.c_str());
  if (ImGui::CollapsingHeader("GPU time per pass")) {
    for (const auto& p : t.passes) ImGui::Text("%-14s %8.2f ms", p.first.c_str(), p.second);
    ImGui::Text("%-14s %8.2f ms", "total", t.total_ms);
  }
  if (file && file->preset) file_actions(*file);
  if (t.atmosphere_ms > 0.01) last_lut_ms_ = t.atmosphere_ms;
  // The groups of the parameter tables (panel_groups), in their order; the engineering switches of
  // each under its own Advanced fold.
  static const std::vector<PanelGroup> groups = panel_groups();
  ImGui::PushItemWidth(150);
  for (const PanelGroup& g : groups) {
    const bool open_at_start = g.group == cloudgen::ParamGroup::Shape || g.group == cloudgen::ParamGroup::LightAndSky;
    if (!ImGui::CollapsingHeader(g.name.c_str(), open_at_start ? ImGuiTreeNodeFlags_DefaultOpen : 0)) continue;
    ImGui::PushID(g.name.c_str());
    for (const PanelWidget& w : g.render) render_widget(s, w);
    if (!g.atmosphere.empty() || !g.atmosphere_advanced.empty())
      ImGui::Text("atmosphere LUTs (last run) %8.2f ms", last_lut_ms_);
    for (const std::string& k : g.atmosphere) atmosphere_widget(s, k);
    if ((!g.render_advanced.empty() || !g.atmosphere_advanced.empty()) && ImGui::TreeNode("Advanced")) {
      for (const PanelWidget& w : g.render_advanced) render_widget(s, w);
      for (const std::string& k : g.atmosphere_advanced) atmosphere_widget(s, k);
      ImGui::TreePop();
    }
    ImGui::PopID();
  }
  ImGui::PopItemWidth();
  ImGui::End();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace cloudviewer
