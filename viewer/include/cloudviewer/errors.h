// Typed exceptions of the viewer library. Library code throws; only main() picks the exit code.
#pragma once
#include <stdexcept>
#include <string>

namespace cloudviewer {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
/// A user-input problem (file, flag, value, what was allowed) already in the message.
class InputError : public Error {
 public:
  using Error::Error;
};
/// OpenGL / EGL / window-system failure (no context, incomplete framebuffer...).
class GlError : public Error {
 public:
  using Error::Error;
};
/// A shader failed to compile or link. what() holds "file:line: log".
class ShaderError : public GlError {
 public:
  ShaderError(const std::string& message, std::string file, int line)
      : GlError(message), file_(std::move(file)), line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

}  // namespace cloudviewer
