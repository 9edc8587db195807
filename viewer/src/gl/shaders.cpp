// Shader sources (embedded or from --shader-dir), #include expansion with #line mapping, and
// compilation with errors reported as FILE:LINE: log.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <epoxy/gl.h>

#include "cloudviewer/errors.h"
#include "cloudviewer/renderer.h"

namespace cloudviewer {

const std::map<std::string, std::string>& embedded_shaders();  // generated embedded_shaders.cpp

std::vector<std::string> embedded_shader_names() {
  std::vector<std::string> names;
  for (const auto& kv : embedded_shaders()) names.push_back(kv.first);
  return names;
}

std::string ShaderSource::load(const std::string& name) const {
  auto over = overrides_.find(name);
  if (over != overrides_.end()) return over->second;
  auto it = embedded_shaders().find(name);
  if (!dir_.empty()) {
    std::ifstream in(dir_ + "/" + name, std::ios::binary);
    // --shader-dir overrides the embedded copies file by file: a header that lives outside
    // viewer/shaders (cloudgen's cloud_type.glsl) comes from the build unless the directory has it.
    if (!in && it != embedded_shaders().end()) return it->second;
    if (!in) throw InputError("shader '" + name + "' not found in --shader-dir " + dir_);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  if (it == embedded_shaders().end()) throw InputError("shader '" + name + "' is not embedded");
  return it->second;
}

void ShaderSource::expand_into(const std::string& name, std::vector<std::string>& files,
                               std::string& out, std::vector<std::string>& stack) const {
  if (std::find(stack.begin(), stack.end(), name) != stack.end())
    throw InputError("shader include cycle through '" + name + "'");
  if (std::find(files.begin(), files.end(), name) != files.end())
    return;  // each file once (GLSL has no #pragma once)
  int number = int(files.size());
  files.push_back(name);
  stack.push_back(name);
  std::istringstream in(load(name));
  std::string line;
  int line_no = 0;
  bool first = stack.size() == 1;
  if (!first) out += "#line 1 " + std::to_string(number) + "\n";
  static const std::regex include_re(R"re(^\s*#\s*include\s+"([^"]+)"\s*$)re");
  std::smatch m;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (std::regex_match(line, m, include_re)) {
      expand_into(m[1].str(), files, out, stack);
      out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(number) + "\n";
      continue;
    }
    out += line + "\n";
    if (first && line_no == 1 && line.rfind("#version", 0) == 0)
      out += "#line 2 " + std::to_string(number) + "\n";
  }
  stack.pop_back();
}

std::string ShaderSource::expand(const std::string& name, std::vector<std::string>& files) const {
  files.clear();
  std::string out;
  std::vector<std::string> stack;
  expand_into(name, files, out, stack);
  return out;
}

unsigned compile_shader_stage(unsigned stage, const ShaderSource& src, const std::string& name) {
  std::vector<std::string> files;
  std::string text = src.expand(name, files);
  GLuint shader = glCreateShader(stage);
  const char* ptr = text.c_str();
  glShaderSource(shader, 1, &ptr, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok) return shader;
  GLint len = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
  std::string log(size_t(std::max(len, 1)), '\0');
  glGetShaderInfoLog(shader, len, nullptr, log.data());
  glDeleteShader(shader);
  log.resize(std::strlen(log.c_str()));
  // Map "S:L(C)" (Mesa) and "S(L)" (NVIDIA) prefixes back to file names through #line.
  static const std::regex loc_re(R"re(^\s*(?:ERROR:\s*)?(\d+)[:(](\d+))re");
  std::istringstream lines(log);
  std::string l, mapped, first_file = name;
  int first_line = 0;
  std::smatch m;
  while (std::getline(lines, l)) {
    if (std::regex_search(l, m, loc_re)) {
      size_t s = std::stoul(m[1].str());
      int ln = std::stoi(m[2].str());
      std::string file = s < files.size() ? files[s] : name;
      if (first_line == 0) {
        first_file = file;
        first_line = ln;
      }
      l = file + ":" + std::to_string(ln) + ": " + l.substr(size_t(m.position(0) + m.length(0)));
    }
    mapped += "  " + l + "\n";
  }
  std::string where = first_file + ":" + std::to_string(first_line);
  const char* version = reinterpret_cast<const char*>(glGetString(GL_SHADING_LANGUAGE_VERSION));
  throw ShaderError("shader compile error in " + where + " (compiling " + name + ", GLSL " +
                        (version ? version : "?") + ")" +
                        (src.dir().empty() ? std::string(" [embedded]") : " [" + src.dir() + "]") +
                        ":\n" + mapped,
                    first_file, first_line);
}

}  // namespace cloudviewer
