// The toolkit's one error hierarchy, shared by cloudgen and cloudviewer. Library code throws these;
// only a program's entry point catches them and picks the exit code (cloudgen/exit_codes.h).
#pragma once

#include <stdexcept>

namespace cloudgen {

/// Base of every error the toolkit throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
/// A user-facing input problem (file, field, value, what was allowed) already in the message.
class InputError : public Error {
 public:
  using Error::Error;
};
/// Reading or writing a file failed (the message names the path and the system's reason).
class IoError : public Error {
 public:
  using Error::Error;
};
/// The machine lacks something the work needs: an OpenGL context, a window system, a device.
class EnvironmentError : public Error {
 public:
  using Error::Error;
};
/// The user interrupted the work (Ctrl-C, SIGTERM); nothing was written or replaced.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

}  // namespace cloudgen
