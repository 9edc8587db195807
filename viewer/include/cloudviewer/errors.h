// Typed exceptions of the viewer library: cloudgen's hierarchy (cloudgen/volume.h), one set of
// types for both programs, plus the OpenGL failures only the viewer has. Library code throws; only
// run_cli picks the exit code, by the toolkit's one rule (exit_code below):
//   1  InputError                 a user-input problem (file, flag, value, what was allowed)
//   2  IoError, GlError           reading/writing a file failed; no OpenGL context, a shader failed
//                                  (I/O and environment)
//   3  anything else              an internal error
#pragma once
#include <exception>
#include <string>

#include "cloudgen/volume.h"

namespace cloudviewer {

using Error = cloudgen::Error;
/// A user-input problem (file, flag, value, what was allowed) already in the message.
using InputError = cloudgen::InputError;
/// Reading or writing a file failed (the message names the path and the system's reason).
using IoError = cloudgen::IoError;

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

/// The exit code of a failure, by the rule above.
int exit_code(const std::exception& e);

}  // namespace cloudviewer
