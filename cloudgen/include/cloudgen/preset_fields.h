// The preset table's rows for an editor (the viewer's panel): each key with its type, range,
// choices, doc and group, and a preset's current values, so a control per key needs no code of
// its own. Kept out of preset.h, which everything includes.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "cloudgen/param_group.h"

namespace cloudgen {

struct PresetField {
  std::string key;      ///< as `--set` spells it: "coverage.low", "towers.list.*.center"
  std::string pointer;  ///< "/coverage/low"
  std::string type;     ///< schema.h's: number, integer, bool, string, vec2, vec3, ivec3, period, array, object
  std::string default_value;  ///< JSON text ("null": unset)
  double lo = 0, hi = 0;      ///< numbers and each element of a vector
  std::vector<std::string> choices;  ///< a string's allowed values (empty: any text)
  std::string range, doc;
  ParamPlace place;
};

/// A list field's key for element i: "shape.sources.*.radius" -> "shape.sources.1.radius" (a key
/// without ".*." comes back unchanged).
std::string list_element_key(const std::string& key, size_t i);

/// Every row of the preset table, in table order.
const std::vector<PresetField>& preset_fields();

/// The value of every key of the preset `path` with `sets` applied, as JSON text keyed by
/// PresetField::key (the table's default where the file does not set it); a key of a list element
/// once per element the preset has, with its index for the "*" ("shape.sources.1.radius").
/// InputError as load_preset when the result is not a valid preset.
std::map<std::string, std::string> preset_values(const std::string& path, const std::vector<std::string>& sets);

}  // namespace cloudgen
