// The field checker and document walker shared by the preset reader, the bench track reader and
// `cloudgen noise` (schema.h).
#include "cloudgen/schema.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cloudgen/json_checked.h"

namespace cloudgen {
namespace {

using json = nlohmann::json;

std::string shown(const json& j) { return json_excerpt(j); }

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> d(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t prev = d[0];
    d[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t cur = d[j];
      d[j] = std::min({d[j] + 1, d[j - 1] + 1, prev + (a[i - 1] != b[j - 1])});
      prev = cur;
    }
  }
  return d[b.size()];
}

bool number_ok(const FieldSpec& f, const json& v, bool integer, const std::string& ptr, const ProblemSink& problem) {
  if (!v.is_number() || (integer && !(v.is_number_integer() || std::floor(v.get<double>()) == v.get<double>()))) {
    problem(ptr, shown(v) + " has the wrong type; expected " + (integer ? "an integer" : "a number") + " in [" +
                     shortest_text(f.lo) + ", " + shortest_text(f.hi) + "]");
    return false;
  }
  const double d = v.get<double>();
  // An integer beyond 2^53 rounds to a double inside the range (2^53 + 1 -> 2^53): compare it exact.
  const bool exact_out = v.is_number_unsigned() && d >= 9007199254740992.0 && f.hi >= 0 &&
                         f.hi < 18446744073709551616.0 && v.get<uint64_t>() > uint64_t(f.hi);
  if (!(d >= f.lo && d <= f.hi) || exact_out) {
    problem(ptr, shown(v) + " is out of range; allowed: " + f.range());
    return false;
  }
  return true;
}

}  // namespace

std::string shortest_text(double v) {
  char buf[40];
  for (int prec = 6; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string FieldSpec::range() const {
  if (!allowed.empty()) return allowed;
  if (!choices.empty()) {
    std::string r;
    for (const std::string& c : choices) r += (r.empty() ? "" : " | ") + c;
    return r;
  }
  if (type == "bool") return "true | false";
  if (type == "string") return "any text";
  if (type == "array") return "list";
  if (type == "strings") return "list of strings";
  if (type == "object") return "KEY: value";
  return std::string(type == "integer" || type == "ivec3" || type == "period" ? "integer" : "number") + " in [" +
         shortest_text(lo) + ", " + shortest_text(hi) + "]";
}

bool check_value(const FieldSpec& f, const json& v, const std::string& ptr, const ProblemSink& problem) {
  const std::string& t = f.type;
  // A key that may be unset takes null to unset it again (`--set shape.floor=null`).
  if (v.is_null() && f.nullable) return true;
  bool ok = true;
  if (t == "number" || t == "integer") {
    ok = number_ok(f, v, t == "integer", ptr, problem);
  } else if (t == "bool") {
    if (!v.is_boolean()) ok = false, problem(ptr, shown(v) + " has the wrong type; expected true or false");
  } else if (t == "string") {
    if (!v.is_string()) {
      ok = false, problem(ptr, shown(v) + " has the wrong type; expected a string" + (f.choices.empty() ? "" : ": " + f.range()));
    } else if (!f.choices.empty() && std::find(f.choices.begin(), f.choices.end(), v.get<std::string>()) == f.choices.end()) {
      ok = false, problem(ptr, shown(v) + " is not allowed; expected one of: " + f.range());
    }
  } else if (t == "vec2" || t == "vec3" || t == "ivec3" || (t == "period" && v.is_array())) {
    const size_t n = t == "vec2" ? 2 : 3;
    const bool ints = t == "ivec3" || t == "period";
    if (!v.is_array() || v.size() != n) {
      ok = false, problem(ptr, shown(v) + " has the wrong type; expected an array of " + std::to_string(n) + " " +
                                   (ints ? "integers" : "numbers") + ", each " + f.range());
    } else {
      for (size_t a = 0; a < n && ok; ++a) ok = number_ok(f, v[a], ints, ptr + "/" + std::to_string(a), problem);
    }
  } else if (t == "period") {
    ok = number_ok(f, v, true, ptr, problem);
  } else if (t == "array") {
    if (!v.is_array()) ok = false, problem(ptr, shown(v) + " has the wrong type; expected a list");
  } else if (t == "strings") {
    if (!v.is_array()) {
      ok = false, problem(ptr, shown(v) + " has the wrong type; expected a " + f.range());
    } else {
      for (size_t i = 0; i < v.size(); ++i)
        if (!v[i].is_string())
          ok = false, problem(ptr + "/" + std::to_string(i), shown(v[i]) + " has the wrong type; expected a string");
    }
  } else if (t == "object") {
    if (!v.is_object()) {
      ok = false, problem(ptr, shown(v) + " has the wrong type; expected an object of KEY: value");
    } else {
      for (auto& [k, val] : v.items()) {
        const bool name_ok = !k.empty() && k.size() <= 64 && std::all_of(k.begin(), k.end(), [](char c) {
                               return std::islower((unsigned char)c) || std::isdigit((unsigned char)c) || c == '_';
                             });
        if (!name_ok) ok = false, problem(ptr + "/" + k, "not a setting name (lower-case letters, digits, _)");
        else if (!(val.is_number() || val.is_boolean() || val.is_string()))
          ok = false, problem(ptr + "/" + k, shown(val) + " has the wrong type; expected a number, true/false or a string");
      }
    }
  }
  return ok;
}

Schema::Schema(std::vector<FieldSpec> fields) : fields_(std::move(fields)) {
  for (size_t i = 0; i < fields_.size(); ++i) {
    by_name_[fields_[i].name] = i;
    // Every proper prefix of a field's pointer is a container object (or list element).
    const std::string& ptr = fields_[i].name;
    for (size_t k = ptr.find('/', 1); k != std::string::npos; k = ptr.find('/', k + 1)) containers_.insert(ptr.substr(0, k));
  }
}

const FieldSpec* Schema::find(const std::string& name) const {
  auto it = by_name_.find(name);
  return it == by_name_.end() ? nullptr : &fields_[it->second];
}

std::vector<std::string> Schema::keys_under(const std::string& parent) const {
  std::set<std::string> keys;
  for (const auto& [ptr, i] : by_name_)
    if (ptr.rfind(parent + "/", 0) == 0) {
      const std::string rest = ptr.substr(parent.size() + 1);
      keys.insert(rest.substr(0, rest.find('/')));
    }
  return {keys.begin(), keys.end()};
}

std::string Schema::suggest(const std::string& parent, const std::string& key) const {
  std::string best;
  size_t bd = 3;
  const std::vector<std::string> siblings = keys_under(parent);
  for (const auto& s : siblings) {
    const size_t d = edit_distance(key, s);
    if (d < bd) bd = d, best = s;
  }
  std::string allowed;
  for (const auto& s : siblings) allowed += (allowed.empty() ? "" : ", ") + s;
  return (best.empty() ? "" : " (did you mean \"" + best + "\"?)") + std::string("; allowed here: ") + allowed;
}

void Schema::walk(const json& doc, const ProblemSink& problem, const Visit& visit) const {
  walk(doc, "", "", {}, problem, visit);
}

void Schema::walk(const json& j, const std::string& ptr, const std::string& pattern, const std::vector<size_t>& idx,
                  const ProblemSink& problem, const Visit& visit) const {
  if (const FieldSpec* f = find(pattern)) {
    if (!check_value(*f, j, ptr, problem)) return;
    if (visit) visit(*f, j, ptr, idx);
    if (f->type != "array") return;
    std::string keys;
    for (const std::string& k : keys_under(pattern + "/*")) keys += (keys.empty() ? "" : ", ") + k;
    for (size_t i = 0; i < j.size(); ++i) {
      std::vector<size_t> sub = idx;
      sub.push_back(i);
      const std::string eptr = ptr + "/" + std::to_string(i);
      if (!j[i].is_object()) {
        problem(eptr, "expected an object {" + keys + "}, got " + shown(j[i]));
        continue;
      }
      // List elements start from the element defaults of the table.
      if (visit)
        for (const FieldSpec& e : fields_)
          if (e.name.rfind(pattern + "/*/", 0) == 0) visit(e, json::parse(e.default_value), eptr, sub);
      walk(j[i], eptr, pattern + "/*", sub, problem, visit);
    }
    return;
  }
  if (!j.is_object()) {
    problem(ptr.empty() ? "/" : ptr, "expected an object, got " + shown(j));
    return;
  }
  for (auto& [key, value] : j.items()) {
    const std::string cptr = ptr + "/" + key, cpat = pattern + "/" + key;
    if (by_name_.count(cpat) || containers_.count(cpat)) walk(value, cptr, cpat, idx, problem, visit);
    else problem(cptr, "unknown key" + suggest(pattern, key));
  }
}

}  // namespace cloudgen
