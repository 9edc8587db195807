// Help text for people: every line of `--help` and `--help-params` of both programs fits in
// kHelpWidth characters. Parameter tables keep one doc string per key; these functions lay it out.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace cloudgen {

inline constexpr std::size_t kHelpWidth = 100;
/// CLI11's name column (its default): option descriptions start here.
inline constexpr std::size_t kHelpColumn = 30;

/// `text` with its words in lines of at most `width` characters, breaking at spaces only (a word
/// longer than `width` stands alone on its line). Existing line breaks are kept.
std::string wrap_words(const std::string& text, std::size_t width);

/// One entry of a parameter list: "  HEAD\n" then DOC wrapped to kHelpWidth, indented six spaces.
std::string help_entry(const std::string& head, const std::string& doc);

/// Wraps every option and subcommand description of a CLI11 app (and its subcommands, depth
/// first) to the width CLI11's formatter leaves after its name column. Footers are left as they
/// are: examples keep their lines.
template <class App>
void wrap_cli_help(App& app) {
  for (auto* opt : app.get_options()) opt->description(wrap_words(opt->get_description(), kHelpWidth - kHelpColumn));
  const std::function<bool(App*)> every = [](App*) { return true; };
  for (App* sub : app.get_subcommands(every)) {
    sub->description(wrap_words(sub->get_description(), kHelpWidth - kHelpColumn));
    wrap_cli_help(*sub);
  }
}

/// The value rules every option of both programs shares (docs/robustness.md, "Inputs"): an empty
/// value (`--resolution ""`) is refused instead of silently meaning the default, and a number
/// option refuses "nan" and "inf" (which the conversion would accept). Subcommands too.
template <class App>
void check_cli_values(App& app) {
  for (auto* opt : app.get_options()) {
    if (opt->get_type_size() == 0) continue;  // a flag: no value
    const std::string type = opt->get_type_name();
    const bool number = type.rfind("FLOAT", 0) == 0 || type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0 ||
                        type.rfind("NUMBER", 0) == 0;
    opt->check(
        [number](const std::string& v) -> std::string {
          if (v.empty()) return "an empty value; give one, or leave the option out for its default";
          if (!number) return "";
          std::string l;
          for (char c : v) l += char(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
          if (l.find("nan") != std::string::npos || l.find("inf") != std::string::npos)
            return "\"" + v + "\" is not a finite number";
          return "";
        },
        "", "");
  }
  const std::function<bool(App*)> every = [](App*) { return true; };
  for (App* sub : app.get_subcommands(every)) check_cli_values(*sub);
}

}  // namespace cloudgen
