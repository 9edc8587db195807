// cloudgen: parse, run, report. All logic lives in cloudgen_lib and each command in its own file
// (commands.h); this file dispatches and maps errors to exit codes (0 ok, 1 bad input, 2 I/O
// failure, 3 internal error, 130 interrupted).
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>

#include "cloudgen/exit_codes.h"
#include "cloudgen/help_text.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/interrupt.h"
#include "commands.h"

int main(int argc, char** argv) {
  using namespace cloudgen;
  using namespace cloudgen::cli;
  install_interrupt_policy();  // SIGINT/SIGTERM/SIGPIPE (cloudgen/interrupt.h)
  InputScope inputs;  // no output of this run may replace a file it reads (cloudgen/input_scope.h)
  // A file-size limit (ulimit -f) then fails the write with EFBIG, reported like a full disk,
  // instead of killing the process mid-write.
  std::signal(SIGXFSZ, SIG_IGN);

  CLI::App app{"cloudgen: bake procedural cloud volumes from tileable noise.\n"
               "Presets (JSON) go through noise -> height profile -> towers -> coverage -> threshold -> channels\n"
               "-> occupancy, and export as OpenVDB (Blender, VFX) or RGBA 3D textures (game engines)."};
  app.require_subcommand(1);
  app.footer("Run `cloudgen COMMAND --help` for each command. Examples:\n"
             "  cloudgen generate presets/cumulus.json -o out/cumulus.vdb -o out/cumulus.ktx2\n"
             "  cloudgen generate thesis -o out/thesis.vdb --set threshold=0.4 --seed 7\n"
             "  cloudgen validate presets/stratus.json\n"
             "  cloudgen info out/cumulus.vdb");
  std::function<void()> run;

  add_generate_command(app, run);
  add_validate_command(app, run);
  add_info_command(app, run);
  add_presets_command(app, run);
  add_noise_command(app, run);
  add_phase_command(app, run);
  add_flowmap_command(app, run);
  add_weather_map_command(app, run);
  add_shape_command(app, run);
  add_blender_command(app, run);
  add_scale_commands(app, run);

  try {
    wrap_cli_help(app);
    check_cli_values(app);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints the message (or the help)
    return finish_stdout(rc == 0 ? kExitOk : kExitInput);
  }
  try {
    if (run) run();
  } catch (const Cancelled&) {
    std::fprintf(stderr, "\ninterrupted: no output was written or replaced\n");
    return finish_stdout(kExitInterrupted);
  } catch (...) {
    const std::exception_ptr e = std::current_exception();
    std::fprintf(stderr, "%s\n", error_message_of(e).c_str());
    return finish_stdout(exit_code_of(e));
  }
  if (g_cancel) {
    if (!g_cancel_reported) std::fprintf(stderr, "interrupted\n");
    return finish_stdout(kExitInterrupted);
  }
  return finish_stdout(kExitOk);
}
