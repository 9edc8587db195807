// The one row type of the viewer's parameter tables (render.* over RenderSettings, atmosphere.*
// over AtmosphereSettings): each key declared once, driving `--set`, validation, `--help-params`,
// the generated reference (docs/reference/viewer-params.md) and the window's panel.
#pragma once
#include <functional>
#include <utility>
#include <string>
#include <vector>

#include "cloudgen/param_group.h"

namespace cloudviewer {

enum class ParamKind { Bool, Int, Float, Enum, FloatOrAuto };

/// One parameter of settings S.
template <class S>
struct Param {
  std::string key;    ///< after the table's prefix ("render.", "atmosphere.")
  std::string type;   ///< bool, int, float, enum
  std::string range;  ///< allowed values, as text
  std::string doc;
  std::function<void(S&, const std::string&)> set;  ///< throws InputError naming key, value and range
  std::function<std::string(const S&)> get;
  ParamKind kind = ParamKind::Float;
  double lo = 0, hi = 0;             ///< Int, Float, FloatOrAuto: the allowed range
  std::vector<std::string> choices;  ///< Enum: the names, in code order
  cloudgen::ParamGroup group = cloudgen::ParamGroup::Unset;  ///< the panel's and the docs' group
  bool advanced = false;             ///< an engineering switch (under the group's Advanced fold)

  /// Places the row in a group: `table.push_back(real(...).in(ParamGroup::Detail))`.
  Param in(cloudgen::ParamGroup g, bool is_advanced = false) && {
    group = g, advanced = is_advanced;
    return std::move(*this);
  }
};

}  // namespace cloudviewer
