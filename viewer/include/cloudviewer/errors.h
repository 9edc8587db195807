// Typed exceptions of the viewer library: the toolkit's one hierarchy (cloudgen/errors.h), plus the
// OpenGL failures only the viewer has. Library code throws; only run_cli picks the exit code, by the
// toolkit's one rule, cloudgen::exit_code_of (cloudgen/exit_codes.h): 1 bad input, 2 I/O or
// environment (a GlError: no OpenGL context, a shader that failed), 3 internal, 130 interrupted.
#pragma once
#include <exception>
#include <string>

#include "cloudgen/errors.h"

namespace cloudviewer {

using Error = cloudgen::Error;
/// A user-input problem (file, flag, value, what was allowed) already in the message.
using InputError = cloudgen::InputError;
/// Reading or writing a file failed (the message names the path and the system's reason).
using IoError = cloudgen::IoError;

/// OpenGL / EGL / window-system failure (no context, incomplete framebuffer...).
class GlError : public cloudgen::EnvironmentError {
 public:
  using cloudgen::EnvironmentError::EnvironmentError;
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
