// The cloudviewer command line: parse, run (window, headless, bench), report. main() only calls
// run_cli and returns its code.
#pragma once
#include <iosfwd>
#include <string>
#include <vector>

namespace cloudviewer {

/// Runs the viewer with argv-style arguments. Never throws; messages go to `err`. Returns the
/// process exit code by the toolkit's one rule (cloudgen/exit_codes.h): 0 success, 1 user-input
/// error, 2 I/O or environment (a file, OpenGL, shaders), 3 internal error, 130 interrupted.
int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace cloudviewer
