// Text made safe to print (printable.h).
#include "cloudgen/printable.h"

#include <sstream>

#include <cstdio>

namespace cloudgen {

std::string printable(const std::string& s, bool keep_newlines) {
  std::string out;
  out.reserve(s.size());
  for (unsigned char c : s) {
    if ((c < 0x20 && !(keep_newlines && (c == '\n' || c == '\t'))) || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += char(c);
    }
  }
  return out;
}

std::string human_bytes(unsigned long long b) {
  std::ostringstream o;
  o.precision(3);
  if (b >= (1ull << 30)) o << b / double(1ull << 30) << " GiB";
  else o << b / double(1ull << 20) << " MiB";
  return o.str();
}

}  // namespace cloudgen
