// `cloudgen validate`: check presets and print every problem.
#include <cstdio>
#include <memory>

#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "commands.h"

namespace cloudgen::cli {

void add_validate_command(CLI::App& app, std::function<void()>& run) {
  auto vpath = std::make_shared<std::vector<std::string>>();
  auto vsets = std::make_shared<std::vector<std::string>>();
  CLI::App* val = app.add_subcommand("validate", "Check presets; print every problem (exit 1) or nothing (exit 0).");
  val->add_option("preset", *vpath, "Preset file(s) or shipped preset names")->required();
  val->add_option("--set", *vsets, "Overrides, as for generate");
  val->callback([vpath, vsets, &run] {
    run = [vpath, vsets] {
      size_t bad = 0;
      for (const auto& p : *vpath) {
        auto problems = check_preset(resolve_preset_path(p), *vsets);
        for (const auto& m : problems) std::fprintf(stderr, "%s\n", printable(m).c_str());
        bad += !problems.empty();
        if (problems.empty()) std::printf("%s: ok\n", printable(resolve_preset_path(p)).c_str());
      }
      if (bad) throw InputError(std::to_string(bad) + " preset(s) have problems");
    };
  });
}

}  // namespace cloudgen::cli
