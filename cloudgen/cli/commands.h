// cloudgen subcommands, registered on the CLI11 app by main.cpp.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>

namespace cloudgen::cli {

/// Set by SIGINT/SIGTERM; long work checks it and stops, leaving no partial output.
extern std::atomic<bool> g_cancel;

/// A progress bar on stderr, drawn only when stderr is a terminal and not --quiet.
std::function<void(double)> progress_bar(const std::string& label, bool quiet);

void add_noise_command(CLI::App& app, std::function<void()>& run);
void add_phase_command(CLI::App& app, std::function<void()>& run);
void add_blender_command(CLI::App& app, std::function<void()>& run);

/// "cumulus" -> the shipped presets/cumulus.json when no such file exists in the working folder.
std::string resolve_preset_path(const std::string& p);

}  // namespace cloudgen::cli
