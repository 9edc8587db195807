// Text from files, presets and flags made safe to print.
#pragma once

#include <string>

namespace cloudgen {

/// `s` with control characters (and, unless keep_newlines, newlines) written as \xNN, so text
/// from a file or preset cannot forge terminal lines or escape sequences.
std::string printable(const std::string& s, bool keep_newlines = false);

/// A byte count for people: "412 MiB", "1.57 GiB" (three significant digits).
std::string human_bytes(unsigned long long bytes);

}  // namespace cloudgen
