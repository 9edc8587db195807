// Reading JSON text from users and files safely: bounded nesting (a 100k-deep value would
// overflow the stack of anything that walks or prints it recursively), duplicate keys refused
// (the last one silently winning hides typos), syntax errors with line and column.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace cloudgen {

inline constexpr size_t kMaxJsonDepth = 64;

/// Parses `text`; throws InputError "<where>: ..." naming the JSON pointer of a duplicate key or
/// of the value nested too deep, or the line and column of a syntax error.
nlohmann::json parse_json_checked(const std::string& text, const std::string& where,
                                  size_t max_depth = kMaxJsonDepth);

/// A value as short, printable text for messages: at most `max_chars` (then "..."), invalid
/// UTF-8 replaced rather than thrown on, control characters escaped. Recursion is bounded
/// because every document was parsed by parse_json_checked.
std::string json_excerpt(const nlohmann::json& j, size_t max_chars = 60);

/// "line L, column C" of byte offset `byte` in `text`.
std::string json_line_col(const std::string& text, size_t byte);

}  // namespace cloudgen
