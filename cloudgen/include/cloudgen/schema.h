// One checker for declared fields: a table of {name, type, range, default, doc} for the keys of a
// JSON document (presets, the viewer's bench tracks) or the values of command-line flags
// (`cloudgen noise`), and one function that checks a value against its entry and says which field,
// which value and what is allowed. The preset reader, the bench track reader and `cloudgen noise`
// declare their fields here instead of checking them by hand. Built as the small cloud_schema
// library (nlohmann-json only) that cloudgen and the viewer both link.
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace cloudgen {

/// One declared field.
struct FieldSpec {
  std::string name;  ///< JSON pointer ("/keys/*/eye": "*" is any list index) or a flag ("--octaves")
  /// "number", "integer", "bool", "string", "vec2", "vec3", "ivec3" (3 integers), "period" (an
  /// integer or 3), "array" (a list of objects, each walked with the fields "NAME/*/..."), "strings"
  /// (a list of strings), "object" (KEY: number, bool or string, KEY in lower-case letters, digits, _).
  std::string type;
  std::string default_value;  ///< as JSON text ("null": unset)
  std::string doc;
  double lo = -1e300, hi = 1e300;    ///< numbers, and each element of vec2 / vec3 / ivec3 / period
  std::vector<std::string> choices;  ///< a string's allowed values (empty: any text)
  std::string allowed;               ///< the allowed values in words, when the type's own would say less
  bool nullable = false;             ///< null is a valid value: it unsets the field (its reader handles null)

  /// The allowed values in words: `allowed`, else from the type: "integer in [1, 16]",
  /// "volume | world", "true | false", "list", "list of strings"...
  std::string range() const;
};

/// Receives one problem: the pointer (or flag) of the value at fault and what is wrong with it.
using ProblemSink = std::function<void(const std::string& pointer, const std::string& what)>;

/// Checks `v` against `f`: type, range, choices, and for vectors each element. Reports every
/// problem to `problem` with `pointer` (or an element's pointer), as "<value> is out of range;
/// allowed: integer in [1, 16]" and the like. Returns whether `v` is valid.
bool check_value(const FieldSpec& f, const nlohmann::json& v, const std::string& pointer, const ProblemSink& problem);

/// A table of the fields of a JSON document, keyed by pointer.
class Schema {
 public:
  explicit Schema(std::vector<FieldSpec> fields);
  const std::vector<FieldSpec>& fields() const { return fields_; }
  /// The field named `name` (a pointer pattern, "*" for list indices), or null.
  const FieldSpec* find(const std::string& name) const;

  /// Called for every valid field found, with its pointer and list indices ("/keys/2/eye": {2}),
  /// and, when a list element starts, with the default of every field of the element.
  using Visit = std::function<void(const FieldSpec&, const nlohmann::json& value, const std::string& pointer,
                                   const std::vector<size_t>& indices)>;
  /// Walks `doc` (an object): every key must be a field or a container of fields (else "unknown
  /// key" with a did-you-mean and the keys allowed there), every value is checked by check_value,
  /// list elements must be objects; problems go to `problem`, valid fields to `visit`.
  void walk(const nlohmann::json& doc, const ProblemSink& problem, const Visit& visit = {}) const;

 private:
  void walk(const nlohmann::json& j, const std::string& ptr, const std::string& pattern, const std::vector<size_t>& idx,
            const ProblemSink& problem, const Visit& visit) const;
  std::string suggest(const std::string& parent, const std::string& key) const;
  std::vector<std::string> keys_under(const std::string& parent) const;

  std::vector<FieldSpec> fields_;
  std::map<std::string, size_t> by_name_;
  std::set<std::string> containers_;
};

/// The shortest text that reads back as v (0.999, not 0.99899999999999999; 9007199254740992, not
/// 9.0072e+15): how ranges and defaults are shown.
std::string shortest_text(double v);

}  // namespace cloudgen
