// Dear ImGui panel: every entry of the render and atmosphere parameter tables as a slider, checkbox
// or list with its range and default, the table's doc line as the tooltip, and per-pass GPU times.
// The layout comes from panel_groups(): one collapsible header per group of the tables (Shape,
// Detail, Light and sky, ...), the engineering switches under an Advanced fold in each, so a key
// added to a table appears here, in its group, with no code of its own. Follows imgui's examples/example_glfw_opengl3/main.cpp.
#include "app/panel.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <nlohmann/json.hpp>

#include "cloudviewer/controls.h"
#include "cloudviewer/errors.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/preset_fields.h"
#endif

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
      // Off auto: the middle of the range (ground_height 0, time_of_day noon).
      if (ImGui::Checkbox(auto_label.c_str(), &automatic)) set(s, w.key, automatic ? "auto" : text(0.5 * (w.lo + w.hi)));
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

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
// One preset key (cloudgen's preset table): a slider, drag, checkbox or list by its type, within
// its range; a change asks for the edit KEY=VALUE. Lists, objects, free text and unset values are
// shown, not edited.
void preset_widget(const cloudgen::PresetField& f, PanelFile& pf) {
  // In a list element, a key that does not apply to it (a sphere's radii) is unset: not drawn.
  const bool element = f.key.find('*') == std::string::npos && f.pointer.find('*') != std::string::npos;
  const auto it = pf.values.find(f.key);
  if (element && it != pf.values.end() && it->second == "null") return;
  if (it == pf.values.end()) return;
  const nlohmann::json v = nlohmann::json::parse(it->second, nullptr, false);
  const std::string tip = f.doc + " (" + f.type + ", " + f.range + ", default " + f.default_value + ")";
  const char* label = f.key.c_str();
  auto edit = [&](const std::string& value) { pf.edits.push_back(f.key + "=" + value); };
  const double span = f.hi - f.lo;
  if (f.type == "bool" && v.is_boolean()) {
    bool b = v.get<bool>();
    if (ImGui::Checkbox(label, &b)) edit(b ? "true" : "false");
  } else if ((f.type == "integer" || (f.type == "period" && v.is_number())) && v.is_number()) {
    if (span <= 4096) {
      int x = v.get<int>();
      if (ImGui::SliderInt(label, &x, int(f.lo), int(f.hi))) edit(std::to_string(x));
    } else {
      long long x = v.get<long long>();
      if (ImGui::InputScalar(label, ImGuiDataType_S64, &x, nullptr, nullptr, "%lld", ImGuiInputTextFlags_EnterReturnsTrue))
        edit(std::to_string(std::clamp<long long>(x, (long long)f.lo, (long long)f.hi)));
    }
  } else if (f.type == "number" && v.is_number()) {
    float x = v.get<float>();
    const bool log_scale = f.lo > 0 && f.hi / f.lo > 1e3;
    if (span <= 1000 && !log_scale) {
      if (ImGui::SliderFloat(label, &x, float(f.lo), float(f.hi), "%.4g")) edit(text(x));
    } else {
      const float speed = std::max(std::abs(x) * 0.005f, 1e-3f);
      if (ImGui::DragFloat(label, &x, speed, float(f.lo), float(f.hi), "%.4g", ImGuiSliderFlags_AlwaysClamp)) edit(text(x));
    }
  } else if (f.type == "string" && !f.choices.empty() && v.is_string()) {
    int index = -1;
    for (size_t i = 0; i < f.choices.size(); ++i)
      if (f.choices[i] == v.get<std::string>()) index = int(i);
    std::vector<const char*> items;
    for (const std::string& c : f.choices) items.push_back(c.c_str());
    if (ImGui::Combo(label, &index, items.data(), int(items.size())) && index >= 0) edit(f.choices[size_t(index)]);
  } else if ((f.type == "vec2" || f.type == "vec3" || f.type == "ivec3" || f.type == "period") && v.is_array() &&
             (v.size() == 2 || v.size() == 3)) {
    const int n = int(v.size());
    const bool ints = f.type == "ivec3" || f.type == "period";
    float x[3] = {0, 0, 0};
    int xi[3] = {0, 0, 0};
    float largest = 0;
    for (int a = 0; a < n; ++a) {
      x[a] = v[size_t(a)].get<float>(), xi[a] = int(x[a]);
      largest = std::max(largest, std::abs(x[a]));
    }
    bool changed = false;
    if (ints) changed = ImGui::DragScalarN(label, ImGuiDataType_S32, xi, n, 0.2f, nullptr, nullptr, "%d");
    else
      changed = ImGui::DragScalarN(label, ImGuiDataType_Float, x, n, std::max(largest * 0.005f, 1e-3f), nullptr, nullptr,
                                   "%.4g");
    if (changed) {
      std::string value = "[";
      for (int a = 0; a < n; ++a) {
        const double c = std::clamp(ints ? double(xi[a]) : double(x[a]), f.lo, f.hi);
        value += (a ? "," : "") + (ints ? std::to_string((long long)c) : text(c));
      }
      edit(value + "]");
    }
  } else {
    std::string shown = it->second.size() > 40 ? it->second.substr(0, 37) + "..." : it->second;
    ImGui::TextDisabled("%s = %s", label, shown.c_str());
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tip.c_str());
}

// A list's line: its length and an Add button, which appends a copy of the last element (a sphere
// at the volume's centre when shape.sources is empty, an element of the table's defaults for any
// other empty list), as one edit of the whole list ("shape.sources=[...]").
void list_header(const cloudgen::PresetField& f, PanelFile& pf) {
  const auto it = pf.values.find(f.key);
  if (it == pf.values.end()) return;
  nlohmann::json list = nlohmann::json::parse(it->second, nullptr, false);
  if (!list.is_array()) return;
  ImGui::TextDisabled("%s: %zu", f.key.c_str(), list.size());
  ImGui::SameLine();
  ImGui::PushID(f.key.c_str());
  if (ImGui::SmallButton("Add")) {
    if (!list.empty()) {
      list.push_back(list.back());
    } else if (f.key == "shape.sources") {
      const auto at = [&](const char* k) { return nlohmann::json::parse(pf.values.count(k) ? pf.values.at(k) : "null", nullptr, false); };
      const nlohmann::json origin = at("origin"), res = at("resolution"), vs = at("voxel_size");
      if (origin.is_array() && res.is_array() && vs.is_number() && origin.size() == 3 && res.size() == 3) {
        nlohmann::json c = nlohmann::json::array();
        double smallest = 1e300;
        for (int a = 0; a < 3; ++a) {
          const double extent = res[size_t(a)].get<double>() * vs.get<double>();
          c.push_back(origin[size_t(a)].get<double>() + extent / 2);
          smallest = std::min(smallest, extent);
        }
        list.push_back({{"kind", "sphere"}, {"center", c}, {"radius", smallest / 5}});
      }
    } else {
      list.push_back(nlohmann::json::object());
    }
    if (!list.empty()) pf.edits.push_back(f.key + "=" + list.dump());
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("appends a copy of the last element (an empty shape.sources gets a sphere at the volume's centre)");
  ImGui::PopID();
}

// Removes element i of the list `key` ("shape.sources"), as one edit of the whole list.
void remove_element(const std::string& key, size_t i, PanelFile& pf) {
  const auto it = pf.values.find(key);
  if (it == pf.values.end()) return;
  nlohmann::json list = nlohmann::json::parse(it->second, nullptr, false);
  if (!list.is_array() || i >= list.size()) return;
  list.erase(list.begin() + std::ptrdiff_t(i));
  pf.edits.push_back(key + "=" + list.dump());
}

// Whether the preset has a value for `f` (for a list field: in its first element).
bool has_value(const cloudgen::PresetField& f, const PanelFile& pf) {
  return pf.values.count(cloudgen::list_element_key(f.key, 0)) > 0;
}

// The preset's keys of group `g` (advanced or not); true when there is any. A list's elements
// (shape sources, towers) each get a fold with their own keys, edited as "shape.sources.1.radius".
bool preset_widgets(cloudgen::ParamGroup g, bool advanced, PanelFile* pf) {
  if (!pf || !pf->preset) return false;
  bool any = false;
  std::set<std::string> lists_drawn;
  const std::vector<cloudgen::PresetField>& fields = cloudgen::preset_fields();
  for (const cloudgen::PresetField& f : fields) {
    if (f.place.group != g || f.place.advanced != advanced || !has_value(f, *pf)) continue;
    if (!any) ImGui::TextDisabled(advanced ? "preset (advanced)" : "preset");
    any = true;
    if (f.type == "array") {  // a list: its length and Add here, its elements' folds below
      list_header(f, *pf);
      continue;
    }
    const size_t star = f.key.find(".*.");
    if (star == std::string::npos) {
      preset_widget(f, *pf);
      continue;
    }
    const std::string list = f.key.substr(0, star);  // "shape.sources"
    if (!lists_drawn.insert(list).second) continue;
    for (size_t i = 0; pf->values.count(cloudgen::list_element_key(f.key, i)); ++i) {
      // "shape.sources 2: ellipsoid": the element's kind where it has one.
      std::string title = list + " " + std::to_string(i);
      const auto kind = pf->values.find(list + "." + std::to_string(i) + ".kind");
      if (kind != pf->values.end() && kind->second.size() > 2 && kind->second.front() == '"')
        title += ": " + kind->second.substr(1, kind->second.size() - 2);
      if (!ImGui::TreeNode(title.c_str())) continue;
      if (ImGui::SmallButton("Remove")) remove_element(list, i, *pf);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("removes this element from %s (the later ones move up)", list.c_str());
      for (const cloudgen::PresetField& e : fields) {
        if (e.key.rfind(list + ".*.", 0) != 0 || e.place.group != g || e.place.advanced != advanced) continue;
        cloudgen::PresetField one = e;
        one.key = cloudgen::list_element_key(e.key, i);
        preset_widget(one, *pf);
      }
      ImGui::TreePop();
    }
  }
  return any;
}
bool has_preset_widgets(cloudgen::ParamGroup g, bool advanced, const PanelFile* pf) {
  if (!pf || !pf->preset) return false;
  for (const cloudgen::PresetField& f : cloudgen::preset_fields())
    if (f.place.group == g && f.place.advanced == advanced && has_value(f, *pf)) return true;
  return false;
}
#else
bool preset_widgets(cloudgen::ParamGroup, bool, PanelFile*) { return false; }
bool has_preset_widgets(cloudgen::ParamGroup, bool, const PanelFile*) { return false; }
#endif

// The key list's Markdown table rows as plain lines ("F1  the panel on / off"), headers dropped.
std::string plain_key_list(const std::string& md) {
  std::string out, row;
  for (size_t i = 0; i <= md.size(); ++i) {
    if (i < md.size() && md[i] != '\n') {
      row += md[i];
      continue;
    }
    if (!row.empty() && row.rfind("|---", 0) != 0 && row.rfind("| key", 0) != 0) {
      std::string plain;
      for (size_t k = 0; k < row.size(); ++k) {
        if (row[k] == '`') continue;
        if (row[k] == '\\' && k + 1 < row.size() && row[k + 1] == '|') plain += row[++k];  // an escaped |
        else if (row[k] == '|') plain += plain.empty() ? "" : "  ";
        else plain += row[k];
      }
      out += plain + "\n";
    }
    row.clear();
  }
  return out;
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

// Reset view and the bookmark buttons, on one line: a stored bookmark recalls, an empty one stores
// the current camera, Ctrl+click stores over a stored one.
void camera_buttons(PanelCamera& c) {
  ImGui::Checkbox("Reference (path tracer)", &c.reference);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("C: the path tracer's image of this view in place of the preview, refined while the view, "
                      "the sun and the settings stay (every order of scattering: the ground truth)");
  if (c.reference) {
    ImGui::SameLine();
    ImGui::TextDisabled("%lld paths per pixel", c.reference_paths);
  }
  if (ImGui::SmallButton("Reset view")) c.reset = true;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Home: the camera back to the preset's view (the start view)");
  for (int i = 0; i < int(c.stored.size()); ++i) {
    ImGui::SameLine(0, i == 0 ? -1.f : 2.f);
    const std::string label = std::to_string(i + 1) + (c.stored[size_t(i)] ? "*" : "") + "###b";
    ImGui::PushID(i);
    if (ImGui::SmallButton(label.c_str())) {
      if (c.stored[size_t(i)] && !ImGui::GetIO().KeyCtrl) c.recall = i;
      else c.store = i;
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("bookmark %d (%s): a click recalls a stored camera (*) or stores the current one; Ctrl+click or "
                        "Ctrl+%d stores, Shift+%d recalls. Kept for this session only",
                        i + 1, c.stored[size_t(i)] ? "stored" : "empty", i + 1, i + 1);
    ImGui::PopID();
  }
}

}  // namespace

void Panel::draw(RenderSettings& s, const GpuTimings& t, const std::string& hint, PanelFile* file,
                 PanelCamera* camera) {
  if (!visible) return;
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("cloudviewer");
  ImGui::TextUnformatted(hint.c_str());
  if (camera) camera_buttons(*camera);
  if (ImGui::CollapsingHeader("GPU time per pass")) {
    for (const auto& p : t.passes) ImGui::Text("%-14s %8.2f ms", p.first.c_str(), p.second);
    ImGui::Text("%-14s %8.2f ms", "total", t.total_ms);
  }
  if (!help.empty() && ImGui::CollapsingHeader("Keys")) ImGui::TextUnformatted(plain_key_list(help).c_str());
  if (file && file->preset) file_actions(*file);
  if (t.atmosphere_ms > 0.01) last_lut_ms_ = t.atmosphere_ms;
  // The groups of the parameter tables (panel_groups), in their order; the engineering switches of
  // each under its own Advanced fold.
  static const std::vector<PanelGroup> groups = panel_groups();
  if (file && file->preset && !file->edit_status.empty()) ImGui::TextWrapped("%s", file->edit_status.c_str());
  ImGui::PushItemWidth(150);
  for (cloudgen::ParamGroup group : cloudgen::kParamGroups) {
    static const PanelGroup none;
    const PanelGroup* found = &none;
    for (const PanelGroup& g : groups)
      if (g.group == group) found = &g;
    const PanelGroup& g = *found;
    const bool preset_basic = has_preset_widgets(group, false, file), preset_advanced = has_preset_widgets(group, true, file);
    const bool advanced = !g.render_advanced.empty() || !g.atmosphere_advanced.empty() || preset_advanced;
    if (g.render.empty() && g.atmosphere.empty() && !preset_basic && !advanced) continue;
    const bool open_at_start = group == cloudgen::ParamGroup::Shape;  // the others folded: every header in view
    const char* name = cloudgen::param_group_name(group);
    if (!ImGui::CollapsingHeader(name, open_at_start ? ImGuiTreeNodeFlags_DefaultOpen : 0)) continue;
    ImGui::PushID(name);
    if (preset_widgets(group, false, file) && !g.render.empty()) ImGui::TextDisabled("render");
    for (const PanelWidget& w : g.render) render_widget(s, w);
    if (!g.atmosphere.empty() || !g.atmosphere_advanced.empty())
      ImGui::Text("atmosphere LUTs (last run) %8.2f ms", last_lut_ms_);
    for (const std::string& k : g.atmosphere) atmosphere_widget(s, k);
    if (advanced && ImGui::TreeNode("Advanced")) {
      if (preset_widgets(group, true, file) && !g.render_advanced.empty()) ImGui::TextDisabled("render");
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
