// cloudviewer: parse, run, exit code. All logic lives in cloudviewer_lib (src/app.cpp).
#include <iostream>
#include <string>
#include <vector>

#include "cloudgen/exit_codes.h"
#include "cloudgen/interrupt.h"
#include "cloudviewer/app.h"

int main(int argc, char** argv) {
  cloudgen::install_interrupt_policy();  // SIGINT/SIGTERM/SIGPIPE, as cloudgen (cloudgen/interrupt.h)
  std::vector<std::string> args(argv, argv + argc);
  return cloudgen::finish_stdout(cloudviewer::run_cli(args, std::cout, std::cerr));  // stdout checked too
}
