// parse_json_checked: a SAX pass (nlohmann's SAX parser is iterative, so it is safe at any depth)
// checks nesting and duplicate keys before the document is built.
#include "cloudgen/json_checked.h"

#include <set>
#include <vector>

#include "cloudgen/printable.h"
#include "cloudgen/volume.h"

namespace cloudgen {
namespace {

using json = nlohmann::json;

/// Escapes a key for a JSON pointer (RFC 6901: ~ -> ~0, / -> ~1).
std::string pointer_token(const std::string& k) {
  std::string o;
  for (char c : k) o += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
  return o;
}

class StructureCheck : public json::json_sax_t {
 public:
  explicit StructureCheck(size_t max_depth) : max_depth_(max_depth) {}
  std::string problem;
  bool syntax_error = false;

  bool null() override { return element(); }
  bool boolean(bool) override { return element(); }
  bool number_integer(number_integer_t) override { return element(); }
  bool number_unsigned(number_unsigned_t) override { return element(); }
  bool number_float(number_float_t, const string_t&) override { return element(); }
  bool string(string_t&) override { return element(); }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    Frame& f = stack_.back();
    if (!f.keys.insert(k).second) {
      problem = (f.ptr.empty() ? "/" : f.ptr) + ": duplicate key \"" + printable(k) +
                "\" (each key may appear once; the second would silently replace the first)";
      return false;
    }
    f.pending = k;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    syntax_error = true;
    return false;
  }

 private:
  struct Frame {
    bool object;
    std::string ptr, pending;
    size_t index = 0;
    std::set<std::string> keys;
  };
  std::string child_ptr() const {
    if (stack_.empty()) return "";
    const Frame& f = stack_.back();
    return f.ptr + "/" + (f.object ? pointer_token(f.pending) : std::to_string(f.index));
  }
  bool element() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
    return true;
  }
  bool open(bool object) {
    const std::string ptr = child_ptr();
    if (stack_.size() >= max_depth_) {
      problem = (ptr.empty() ? "/" : ptr.substr(0, 200) + (ptr.size() > 200 ? "..." : "")) + ": nested deeper than " +
                std::to_string(max_depth_) + " levels";
      return false;
    }
    stack_.push_back({object, ptr, "", 0, {}});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return element();
  }
  size_t max_depth_;
  std::vector<Frame> stack_;
};

}  // namespace

std::string json_excerpt(const json& j, size_t max_chars) {
  std::string s = j.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > max_chars) s = s.substr(0, max_chars > 3 ? max_chars - 3 : 0) + "...";
  return printable(s);
}

std::string json_line_col(const std::string& text, size_t byte) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') ++line, col = 1;
    else ++col;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}

json parse_json_checked(const std::string& text, const std::string& where, size_t max_depth) {
  StructureCheck check(max_depth);
  bool ok = false;
  try {
    ok = json::sax_parse(text, &check);
  } catch (const json::exception&) {
    check.syntax_error = true;  // reported with its position by the full parse below
  }
  if (!ok && !check.syntax_error && !check.problem.empty()) throw InputError(where + ": " + check.problem);
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    std::string msg = e.what();
    auto pos = msg.find("syntax error");
    throw InputError(where + ": JSON syntax error at " + json_line_col(text, e.byte ? e.byte - 1 : 0) + ": " +
                     printable(pos == std::string::npos ? msg : msg.substr(pos)));
  } catch (const json::exception& e) {  // e.g. out_of_range for a number too large (found by fuzzing)
    throw InputError(where + ": invalid JSON: " + printable(e.what()));
  }
}

}  // namespace cloudgen
