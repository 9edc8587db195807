#include "cloudgen/help_text.h"

#include <sstream>

namespace cloudgen {

std::string wrap_words(const std::string& text, std::size_t width) {
  std::string out;
  std::istringstream lines(text);
  std::string line;
  bool first_line = true;
  while (std::getline(lines, line)) {
    if (!first_line) out += '\n';
    first_line = false;
    // Keep a line's leading indent; wrap the rest.
    const std::size_t lead = line.find_first_not_of(' ');
    if (lead == std::string::npos) continue;
    const std::string indent = line.substr(0, lead);
    std::istringstream words(line.substr(lead));
    std::string word, current = indent;
    while (words >> word) {
      if (current.size() > indent.size() && current.size() + 1 + word.size() > width) {
        out += current + '\n';
        current = indent;
      }
      current += (current.size() > indent.size() ? " " : "") + word;
    }
    out += current;
  }
  if (!text.empty() && text.back() == '\n') out += '\n';
  return out;
}

std::string help_entry(const std::string& head, const std::string& doc) {
  const std::string indent = "      ";
  std::string body = wrap_words(doc, kHelpWidth - indent.size()), out = "  " + head + "\n" + indent;
  for (char c : body) {
    out += c;
    if (c == '\n') out += indent;
  }
  return out + "\n";
}

}  // namespace cloudgen
