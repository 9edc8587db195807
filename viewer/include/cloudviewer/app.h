// The cloudviewer command line: parse, run (window, headless, bench), report. main() only calls
// run_cli and returns its code.
#pragma once
#include <iosfwd>
#include <string>
#include <vector>

namespace cloudviewer {

/// Runs the viewer with argv-style arguments. Returns the process exit code: 0 success,
/// 1 user-input error, 2 I/O or environment error (a file could not be read or written, OpenGL,
/// shaders), 3 internal error (see exit_code in errors.h). Never throws. Messages go to `err`.
int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace cloudviewer
