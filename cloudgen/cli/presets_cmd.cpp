// `cloudgen presets`: list the shipped presets, or print the reference of every preset key.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cloudgen/io.h"
#include "cloudgen/preset.h"
#include "commands.h"

namespace fs = std::filesystem;

namespace cloudgen::cli {

void add_presets_command(CLI::App& app, std::function<void()>& run) {
  CLI::App* pre = app.add_subcommand("presets", "List the shipped presets.");
  auto markdown = std::make_shared<bool>(false);
  pre->add_flag("--markdown", *markdown, "Print the reference of every preset key (docs/presets.md) instead");
  pre->callback([&run, markdown] {
    run = [markdown] {
      if (*markdown) {
        std::printf("%s", params_markdown().c_str());
        return;
      }
      std::vector<fs::path> files;
      for (auto& e : fs::directory_iterator(preset_dir()))
        if (e.path().extension() == ".json") files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (auto& f : files) {
        try {
          Preset p = load_preset(f.string());
          std::printf("%-18s %4ux%ux%u  %s\n", printable(f.stem().string()).c_str(), p.resolution[0],
                      p.resolution[1], p.resolution[2], printable(p.description).c_str());
        } catch (const Error& e) {
          std::printf("%-18s INVALID: %s\n", printable(f.stem().string()).c_str(), printable(e.what(), true).c_str());
        }
      }
    };
  });
}

}  // namespace cloudgen::cli
