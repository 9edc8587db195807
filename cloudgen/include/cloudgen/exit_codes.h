// The exit-code rule of every program of the toolkit (cloudgen and cloudviewer):
//   0 success, 1 bad input (a preset, flag or file that is wrong: the message says what is allowed),
//   2 I/O or environment (disk full, permissions, missing device or library, out of memory),
//   3 internal error (a bug: please report it), 130 interrupted (SIGINT/SIGTERM).
// Exceptions (cloudgen/errors.h) map to codes by type, in this one place for both programs:
//   InputError, noise3d::InvalidParameter                         -> 1
//   IoError, EnvironmentError (cloudviewer's GlError),
//   std::filesystem::filesystem_error, std::ios_base::failure,
//   std::bad_alloc                                                -> 2
//   Cancelled                                                     -> 130
//   anything else                                                 -> 3
#pragma once

#include <exception>
#include <string>

namespace cloudgen {

enum ExitCode : int { kExitOk = 0, kExitInput = 1, kExitIo = 2, kExitInternal = 3, kExitInterrupted = 130 };

/// The exit code of exception `e` under the rule above.
int exit_code_of(const std::exception_ptr& e);
/// What kind of failure code `code` reports, for a message's prefix: "error", "I/O error",
/// "interrupted", "internal error".
const char* exit_kind(int code);
/// Flushes stdout (C stdio and std::cout) and returns `code`, or kExitIo with a line on stderr
/// naming the system's reason when any write to stdout failed (a full disk under `> file`): what a
/// program printed is checked like any file it writes. Call it on the way out of main.
int finish_stdout(int code);

/// The one-line (or, for lists of problems, multi-line) message to print for `e`, control
/// characters escaped: "error: ...", "internal error: ...".
std::string error_message_of(const std::exception_ptr& e);

}  // namespace cloudgen
