// cloudgen subcommands, one file each (NAME_cmd.cpp), registered on the CLI11 app by main.cpp.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/interrupt.h"
#include "cloudgen/io.h"

namespace cloudgen::cli {

/// Set by SIGINT/SIGTERM (cloudgen/interrupt.h); long work checks it and stops, leaving no partial output.
inline std::atomic<bool>& g_cancel = cloudgen::g_interrupted;
/// Set when a command already said what an interrupt left behind (main then exits 130 quietly).
extern bool g_cancel_reported;

/// A progress bar on stderr, drawn only when stderr is a terminal and not --quiet.
std::function<void(double)> progress_bar(const std::string& label, bool quiet);

void add_generate_command(CLI::App& app, std::function<void()>& run);
void add_validate_command(CLI::App& app, std::function<void()>& run);
void add_info_command(CLI::App& app, std::function<void()>& run);
void add_presets_command(CLI::App& app, std::function<void()>& run);
void add_noise_command(CLI::App& app, std::function<void()>& run);
void add_phase_command(CLI::App& app, std::function<void()>& run);
void add_flowmap_command(CLI::App& app, std::function<void()>& run);
void add_weather_map_command(CLI::App& app, std::function<void()>& run);
void add_blender_command(CLI::App& app, std::function<void()>& run);
void add_shape_command(CLI::App& app, std::function<void()>& run);

/// The shipped presets' folder: $CLOUDGEN_PRESET_DIR, else the source tree's presets/.
std::string preset_dir();
/// "cumulus" -> the shipped presets/cumulus.json when no such file exists in the working folder.
std::string resolve_preset_path(const std::string& preset);

/// `cloudgen generate`'s options (generate_cmd.cpp parses them).
struct GenerateArgs {
  std::string preset, format, region, max_memory = "16G", seed, up, lod, voxel_budget;
  std::string texture_pack;  ///< --texture-pack DIR (texture_pack.h)
  std::vector<std::string> outputs, sets;
  uint32_t resolution = 0;
  int threads = 0;
  bool quiet = false, no_skip = false, stats = false, mpi = false;
  std::string frames, fps;  ///< --frames A:B, --fps F (sequence_cmd.cpp)
  bool loop = false;
};
/// generate with --frames / --fps / --loop: the static volume of `p` (read from `preset_path`),
/// baked into one VDB per frame, all staged in one OutputBatch (sequence_cmd.cpp).
void run_generate_sequence(const Preset& p, const std::string& preset_path, const GenerateArgs& a);
/// The CLOUDGEN_TEST_HOLD hook (common.cpp): pauses at `where` until SIGINT/SIGTERM when asked.
void test_hold(const char* where);

// Scale-out (scale_cmd.cpp): `plan`, `merge`, and generate's MPI path.
void add_scale_commands(CLI::App& app, std::function<void()>& run);
/// True with --mpi or when an MPI launcher started this process.
bool mpi_requested(bool mpi_flag);
/// generate over MPI ranks; every rank calls it; rank 0 writes the .vdb outputs and reports.
void run_generate_mpi(const Preset& p, const GenerateOptions& go, const std::vector<std::string>& outputs,
                      const std::vector<Format>& formats, bool quiet, bool stats);

}  // namespace cloudgen::cli
