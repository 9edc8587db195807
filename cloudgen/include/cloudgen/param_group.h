// The groups every parameter table sorts its keys into (the preset's, the viewer's render.*,
// atmosphere.* and motion.*): by what a user does, in the order the window's panel and the
// generated references show them. Each table row names its group and whether it is an engineering
// switch ("advanced": shown under an Advanced fold, listed apart in the docs).
#pragma once
#include <string>

namespace cloudgen {

enum class ParamGroup { Shape, Detail, LightAndSky, Camera, Animation, Output, Quality, Unset };

/// The groups in panel and documentation order (Unset is not one: a row left unset is a bug the
/// tests catch).
inline constexpr ParamGroup kParamGroups[] = {ParamGroup::Shape,     ParamGroup::Detail, ParamGroup::LightAndSky,
                                              ParamGroup::Camera,    ParamGroup::Animation, ParamGroup::Output,
                                              ParamGroup::Quality};

inline const char* param_group_name(ParamGroup g) {
  switch (g) {
    case ParamGroup::Shape: return "Shape";
    case ParamGroup::Detail: return "Detail";
    case ParamGroup::LightAndSky: return "Light and sky";
    case ParamGroup::Camera: return "Camera";
    case ParamGroup::Animation: return "Animation";
    case ParamGroup::Output: return "Output";
    case ParamGroup::Quality: return "Quality and speed";
    case ParamGroup::Unset: break;
  }
  return "(no group)";
}

/// A row's place: its group, and whether it is an engineering switch.
struct ParamPlace {
  ParamGroup group = ParamGroup::Unset;
  bool advanced = false;
};

/// The place of a preset key (its JSON pointer as params() spells it, "/towers/list/*/center"), from
/// the preset table (preset.cpp); Unset for a pointer the table does not have.
ParamPlace preset_param_place(const std::string& pointer);

}  // namespace cloudgen
