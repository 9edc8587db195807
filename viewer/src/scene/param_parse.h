// Value parsing shared by the viewer's parameter tables (render.* in settings.cpp, atmosphere.*
// in atmosphere.cpp): one wording of the errors, one rule for numbers and booleans.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "cloudviewer/errors.h"
#include "cloudviewer/param_table.h"

namespace cloudviewer::param {

inline std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// InputError "--set PREFIX.KEY=VALUE: invalid value, allowed: ALLOWED".
[[noreturn]] inline void bad(const std::string& prefix, const std::string& key, const std::string& value,
                             const std::string& allowed) {
  throw InputError("--set " + prefix + "." + key + "=" + value + ": invalid value, allowed: " + allowed);
}

inline bool parse_bool(const std::string& prefix, const std::string& key, const std::string& v) {
  if (v == "true" || v == "1" || v == "on" || v == "yes") return true;
  if (v == "false" || v == "0" || v == "off" || v == "no") return false;
  bad(prefix, key, v, "true|false");
}

/// The whole text a finite number in [lo, hi].
inline double parse_number(const std::string& prefix, const std::string& key, const std::string& v, double lo,
                           double hi) {
  size_t used = 0;
  double d = 0;
  try {
    d = std::stod(v, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != v.size() || v.empty() || !std::isfinite(d) || d < lo || d > hi)
    bad(prefix, key, v, "a number in [" + fmt(lo) + ", " + fmt(hi) + "]");
  return d;
}

/// An accessor of a member: what the row builders below take, so a row can name a member of a
/// member (`[](auto& s) -> auto& { return s.rayleigh_scattering.x; }`) as well as a member.
template <class S, class T>
auto member(T S::*m) {
  return [m](auto& s) -> auto& { return s.*m; };
}

// The rows of a table with prefix PREFIX over settings S: each parses and checks its value, and
// prints it back, the same way in every table.
template <class S, class At>
Param<S> boolean(const char* prefix, const std::string& key, At at, const std::string& doc) {
  return {key, "bool", "true|false", doc, [=](S& s, const std::string& v) { at(s) = parse_bool(prefix, key, v); },
          [=](const S& s) { return std::string(at(s) ? "true" : "false"); }, ParamKind::Bool, 0, 1, {}};
}
template <class S, class At>
Param<S> real(const char* prefix, const std::string& key, At at, double lo, double hi, const std::string& doc) {
  return {key, "float", "[" + fmt(lo) + ", " + fmt(hi) + "]", doc,
          [=](S& s, const std::string& v) { at(s) = parse_number(prefix, key, v, lo, hi); },
          [=](const S& s) { return fmt(at(s)); }, ParamKind::Float, lo, hi, {}};
}
template <class S, class At>
Param<S> integer(const char* prefix, const std::string& key, At at, int lo, int hi, const std::string& doc) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return {key, "int", range, doc,
          [=](S& s, const std::string& v) {
            const double d = parse_number(prefix, key, v, lo, hi);
            if (d != std::floor(d)) bad(prefix, key, v, "an integer in " + range);
            at(s) = int(d);
          },
          [=](const S& s) { return std::to_string(at(s)); }, ParamKind::Int, double(lo), double(hi), {}};
}

/// The Markdown reference of a table (docs/reference/viewer-params.md): one table per group in
/// the panel's order (cloudgen/param_group.h), a group's engineering switches in a table of their
/// own under it; `prefix` ("atmosphere.") goes before each key, headings are `level` deep ("###").
template <class S>
std::string grouped_markdown(const std::vector<Param<S>>& table, const std::string& prefix, const std::string& level) {
  std::string md;
  const S d{};
  for (cloudgen::ParamGroup g : cloudgen::kParamGroups)
    for (bool advanced : {false, true}) {
      std::string rows;
      for (const Param<S>& p : table) {
        if (p.group != g || p.advanced != advanced) continue;
        std::string range = p.range;
        for (size_t i = 0; (i = range.find('|', i)) != std::string::npos; i += 2) range.replace(i, 1, "\\|");
        rows += "| " + prefix + p.key + " | " + p.type + " | " + range + " | " + p.get(d) + " | " + p.doc + " |\n";
      }
      if (rows.empty()) continue;
      md += level + (advanced ? "# " : " ") + cloudgen::param_group_name(g) + (advanced ? ": advanced" : "") + "\n\n" +
            "| key | type | range | default | meaning |\n|---|---|---|---|---|\n" + rows + "\n";
    }
  return md;
}

}  // namespace cloudviewer::param
