// Value parsing shared by the viewer's parameter tables (render.* in settings.cpp, atmosphere.*
// in atmosphere.cpp): one wording of the errors, one rule for numbers and booleans.
#pragma once

#include <cmath>
#include <sstream>
#include <string>

#include "cloudviewer/errors.h"

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

}  // namespace cloudviewer::param
