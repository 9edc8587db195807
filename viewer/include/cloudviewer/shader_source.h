// The GLSL the renderers compile: embedded at build time or read from --shader-dir, includes
// expanded with #line directives so compile logs name the file and line.
#pragma once
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace cloudviewer {

/// Where the GLSL comes from: the copies embedded at build time, or a directory (`--shader-dir`).
class ShaderSource {
 public:
  explicit ShaderSource(std::string dir = {}) : dir_(std::move(dir)) {}
  /// Text of one file; throws InputError when it does not exist.
  std::string load(const std::string& name) const;
  /// The file with every `#include "x"` expanded once and `#line` directives so compile logs map
  /// back to files. `files` receives the file name of each source-string number.
  std::string expand(const std::string& name, std::vector<std::string>& files) const;
  const std::string& dir() const { return dir_; }
  /// Replaces one file's text (before --shader-dir and the embedded copies): the renderer's
  /// compile-time switches (nanovdb_storage.glsl, modes.glsl).
  void set_override(const std::string& name, std::string text) { overrides_[name] = std::move(text); }
  void clear_override(const std::string& name) { overrides_.erase(name); }

 private:
  void expand_into(const std::string& name, std::vector<std::string>& files, std::string& out,
                   std::vector<std::string>& stack) const;
  std::string dir_;
  std::map<std::string, std::string> overrides_;
};

/// Names of the embedded shader files.
std::vector<std::string> embedded_shader_names();

/// Compiles one stage; on failure throws ShaderError with "FILE:LINE: log" (file and line mapped
/// through the #line directives) for the first error. Needs a current GL context.
unsigned compile_shader_stage(unsigned stage, const ShaderSource& src, const std::string& name);

}  // namespace cloudviewer
