// `cloudgen info`: describe files cloudgen wrote.
#include <cstdio>
#include <memory>

#include "cloudgen/io.h"
#include "commands.h"

namespace cloudgen::cli {

void add_info_command(CLI::App& app, std::function<void()>& run) {
  auto ipath = std::make_shared<std::vector<std::string>>();
  CLI::App* info = app.add_subcommand("info", "Describe a .vdb, .nvdb, .raw (+ .json) or .ktx2 file: grids, sizes, ranges.");
  info->add_option("file", *ipath, "File(s) written by cloudgen")->required();
  info->callback([ipath, &run] {
    run = [ipath] {
      for (const auto& f : *ipath) std::printf("%s", describe_file(f).c_str());  // escaped inside
    };
  });
}

}  // namespace cloudgen::cli
