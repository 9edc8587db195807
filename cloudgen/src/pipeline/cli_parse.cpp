#include "cloudgen/cli_parse.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "cloudgen/io.h"
#include "cloudgen/volume.h"

namespace cloudgen {
namespace {

std::string shown(const std::string& s) { return "\"" + printable(s.size() > 80 ? s.substr(0, 77) + "..." : s) + "\""; }

bool all_digits(const std::string& s) {
  if (s.empty() || s.size() > 20) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

}  // namespace

uint64_t parse_uint(const std::string& s, const std::string& flag, uint64_t max) {
  const std::string allowed = "; allowed: an integer in [0, " + std::to_string(max) + "]";
  if (!all_digits(s)) throw InputError(flag + ": " + shown(s) + " is not a whole number" + allowed);
  errno = 0;
  const unsigned long long v = std::strtoull(s.c_str(), nullptr, 10);
  if (errno == ERANGE || v > max) throw InputError(flag + ": " + s + " is out of range" + allowed);
  return v;
}

Region parse_region(const std::string& s, const std::array<uint32_t, 3>& dims, const std::string& flag) {
  const std::string form = " should be X,Y,Z:W,H,D (origin and extent in voxels, each extent at least 1)";
  const size_t colon = s.find(':');
  if (colon == std::string::npos || s.find(':', colon + 1) != std::string::npos || s.back() == ',' ||
      s.find(",:") != std::string::npos || s.find(",,") != std::string::npos)
    throw InputError(flag + ": " + shown(s) + form);
  Region r;
  for (int part = 0; part < 2; ++part) {
    std::stringstream ss(part == 0 ? s.substr(0, colon) : s.substr(colon + 1));
    std::string tok;
    int n = 0;
    for (; std::getline(ss, tok, ','); ++n) {
      if (n >= 3 || !all_digits(tok)) throw InputError(flag + ": " + shown(s) + form);
      const uint64_t v = parse_uint(tok, flag, 0xffffffffull);
      (part == 0 ? r.origin : r.extent)[n] = uint32_t(v);
    }
    if (n != 3) throw InputError(flag + ": " + shown(s) + form);
  }
  for (int a = 0; a < 3; ++a) {
    if (r.extent[a] < 1) throw InputError(flag + ": " + shown(s) + ": extent " + "WHD"[a] + " is 0;" + form);
    if (uint64_t(r.origin[a]) + r.extent[a] > dims[a])
      throw InputError(flag + ": " + shown(s) + " reaches voxel " + std::to_string(uint64_t(r.origin[a]) + r.extent[a]) +
                       " on " + "xyz"[a] + " but the volume is " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) +
                       "x" + std::to_string(dims[2]) + " voxels");
  }
  return r;
}

std::vector<double> parse_number_list(const std::string& s, const std::string& flag, size_t n1, size_t n3) {
  std::vector<double> v;
  std::stringstream ss(s);
  for (std::string t; std::getline(ss, t, ',');) {
    char* end = nullptr;
    const double d = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(d))
      throw InputError(flag + ": " + shown(s) + " is not a list of finite numbers");
    v.push_back(d);
  }
  if (!s.empty() && s.back() == ',') throw InputError(flag + ": " + shown(s) + " ends with a comma");
  if (v.size() != n1 && v.size() != n3)
    throw InputError(flag + ": expected " + std::to_string(n1) + (n1 != n3 ? " or " + std::to_string(n3) : "") +
                     " comma-separated numbers, got " + shown(s));
  return v;
}

uint64_t parse_bytes(const std::string& s, const std::string& flag) {
  const std::string form = " is not a size like 2G, 512M, 64K or 1000000 (bytes)";
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end == s.c_str()) throw InputError(flag + ": " + shown(s) + form);
  const std::string suf(end);
  const double m = suf.empty() || suf == "B" ? 1 : suf == "K" ? 1024.0 : suf == "M" ? 1048576.0 : suf == "G" ? 1073741824.0
                 : suf == "T" ? 1099511627776.0 : -1;
  if (m < 0 || !std::isfinite(v) || v <= 0 || v * m >= 4.6e18) throw InputError(flag + ": " + shown(s) + form);
  return uint64_t(v * m);
}

}  // namespace cloudgen
