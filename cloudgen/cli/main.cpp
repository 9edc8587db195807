// cloudgen: parse, run, report. All logic lives in cloudgen_lib; this file maps errors to exit codes
// (0 ok, 1 bad input, 2 I/O failure, 3 internal error, 130 interrupted).
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sstream>

#include "cloudgen/cli_parse.h"
#include "cloudgen/exit_codes.h"
#include "cloudgen/help_text.h"
#include "cloudgen/generate.h"
#include "cloudgen/view.h"
#include "cloudgen/io.h"
#include "cloudgen/motion.h"
#include "cloudgen/preset.h"
#include "commands.h"

namespace fs = std::filesystem;

namespace cloudgen::cli {

std::atomic<bool> g_cancel{false};
bool g_cancel_reported = false;

std::function<void(double)> progress_bar(const std::string& label, bool quiet) {
  if (quiet || !::isatty(STDERR_FILENO)) return {};
  auto mtx = std::make_shared<std::mutex>();
  auto last = std::make_shared<int>(-1);
  auto t0 = std::chrono::steady_clock::now();
  return [=](double f) {
    std::lock_guard<std::mutex> lock(*mtx);
    int pct = int(f * 100);
    if (pct == *last) return;
    *last = pct;
    const int w = 30, fill = int(f * w);
    double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "\r%-10s [%s%s] %3d%%  %.1fs", label.c_str(), std::string(fill, '#').c_str(),
                 std::string(w - fill, '.').c_str(), pct, el);
    if (f >= 1) std::fprintf(stderr, "\n");
  };
}

namespace {

void on_signal(int) { g_cancel = true; }

std::string preset_dir() {
  if (const char* e = std::getenv("CLOUDGEN_PRESET_DIR")) return e;
  return std::string(CLOUD_SOURCE_DIR) + "/presets";
}

/// "cumulus" -> presets/cumulus.json when no such file exists in the working folder.
std::string resolve_preset(const std::string& p) {
  if (fs::exists(p)) return p;
  fs::path shipped = fs::path(preset_dir()) / (p + (fs::path(p).extension().empty() ? ".json" : ""));
  if (fs::exists(shipped)) return shipped.string();
  return p;  // load_preset reports the missing file
}

std::string human(uint64_t b) {
  std::ostringstream o;
  o.precision(3);
  if (b >= (1ull << 30)) o << b / double(1ull << 30) << " GiB";
  else o << b / double(1ull << 20) << " MiB";
  return o.str();
}

}  // namespace

/// Test hook (tests/test_cloudgen.cpp): CLOUDGEN_TEST_HOLD=generate pauses at the first progress
/// report, =commit pauses with every output staged but none published (=frames: a sequence with
/// its first frame staged); each prints a line and waits for SIGINT/SIGTERM, so a test can
/// interrupt at a known point without sleeping.
void test_hold(const char* where) {
  const char* e = std::getenv("CLOUDGEN_TEST_HOLD");
  if (!e || std::string(e) != where) return;
  std::fprintf(stderr, "cloudgen: test hold at %s\n", where);
  std::fflush(stderr);
  while (!g_cancel) ::usleep(1000);
}

namespace {

void run_generate(const GenerateArgs& a) {
  std::vector<std::string> sets = a.sets;
  if (!a.seed.empty()) sets.push_back("seed=" + std::to_string(parse_uint(a.seed, "--seed", kMaxSeed)));
  if (!a.up.empty()) sets.push_back("export.vdb.up=" + a.up);
  const std::string path = resolve_preset(a.preset);
  Preset p = load_preset(path, sets);
  if (a.resolution) rescale(p, a.resolution);
  if (!a.frames.empty() || !a.fps.empty() || a.loop) return run_generate_sequence(p, path, a);
  if (a.outputs.empty()) throw InputError("-o/--output: give at least one output file (.vdb, .nvdb, .raw, .ktx2, .png, .exr)");
  const ExportOptions& eo = p.export_options;
  std::vector<Format> formats;
  bool detail = false;
  // Every file of every output is claimed before any work: an output that would replace the
  // preset, or a sidecar that would collide with another output, is refused up front.
  OutputBatch batch;
  batch.protect(path, "the input preset " + path);
  for (const auto& o : a.outputs) {
    Format f = a.format.empty() ? format_from_path(o) : parse_format(a.format);
    formats.push_back(f);
    detail |= needs_detail(f, eo);
    for (const OutputFile& of : output_files(o, f, true)) batch.claim(of.path, of.role);
  }
  const bool mpi = mpi_requested(a.mpi);  // ranks hold sparse bricks, not the dense volume
  const uint64_t need = memory_estimate(p, detail), limit = parse_bytes(a.max_memory, "--max-memory");
  if (!mpi && need > limit)
    throw InputError(path + ": resolution " + std::to_string(p.resolution[0]) + "x" + std::to_string(p.resolution[1]) + "x" +
                     std::to_string(p.resolution[2]) + " needs about " + human(need) + ", more than --max-memory " +
                     a.max_memory + " (lower /resolution or use --resolution N)");
  GenerateOptions go;
  go.threads = a.threads;
  go.detail = detail;
  // Only baked VDB / NanoVDB outputs: the detail channels matter only where the erosion is baked
  // (all three channels and a non-zero erosion: the viewer's rule), and there only where density
  // is non-zero. The files' bytes are the same either way.
  bool baked_only = eo.vdb_detail && eo.vdb_bake_erosion;
  for (Format f : formats) baked_only = baked_only && (f == Format::Vdb || f == Format::Nvdb);
  if (baked_only) {
    const bool erodes = p.channels[1].enabled && p.channels[2].enabled && p.channels[3].enabled &&
                        look_of_view(p.view, path).erosion > 0;
    if (erodes) go.detail_only_in_cloud = true;
    else go.detail = false;
  }
  go.skip_empty = !a.no_skip;
  go.cancel = &g_cancel;
  auto bar = progress_bar("generate", a.quiet);
  auto held = std::make_shared<std::atomic<bool>>(false);
  go.progress = [bar, held](double f) {
    if (!held->exchange(true)) test_hold("generate");
    if (bar) bar(f);
  };
  if (!a.region.empty()) {
    const Region r = parse_region(a.region, p.resolution);
    go.region_origin = r.origin;
    go.region_extent = r.extent;
  }
  if (mpi) return run_generate_mpi(p, go, a.outputs, formats, a.quiet, a.stats);
  GenerateStats st;
  Volume v = generate(p, go, &st);
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < a.outputs.size(); ++i) {
    if (g_cancel) throw Cancelled();
    write_volume(v, a.outputs[i], formats[i], eo, batch);
  }
  test_hold("commit");
  if (g_cancel) throw Cancelled();
  batch.commit();
  if (!a.quiet)
    for (size_t i = 0; i < a.outputs.size(); ++i)
      std::fprintf(stderr, "wrote %s (%s)\n", printable(a.outputs[i]).c_str(), format_name(formats[i]));
  const double write_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!a.quiet || a.stats) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    std::fprintf(stderr,
                 "%s: %ux%ux%u voxels, %zu active (%.2f%%), bricks %zu (%zu skipped, %zu with detail), "
                 "generate %.3f s, write %.3f s, peak memory %s\n",
                 printable(p.name).c_str(), v.dims[0], v.dims[1], v.dims[2], st.active_voxels,
                 100.0 * st.active_voxels / std::max<size_t>(1, v.voxel_count()), st.bricks, st.bricks_skipped,
                 st.detail_bricks, st.seconds, write_s, human(uint64_t(ru.ru_maxrss) * 1024).c_str());
  }
  if (g_cancel) {
    std::fprintf(stderr, "interrupted after every output was complete and in place\n");
    g_cancel_reported = true;  // main exits 130 without claiming nothing was written
  }
}

}  // namespace

std::string resolve_preset_path(const std::string& p) { return resolve_preset(p); }

}  // namespace cloudgen::cli

int main(int argc, char** argv) {
  using namespace cloudgen;
  using namespace cloudgen::cli;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
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

  auto ga = std::make_shared<GenerateArgs>();
  CLI::App* gen = app.add_subcommand("generate", "Generate a cloud volume from a preset and export it.");
  gen->add_option("preset", ga->preset, "Preset file, or the name of a shipped preset (see `cloudgen presets`)")->required();
  gen->add_option("-o,--output", ga->outputs, "Output file; repeat for several formats from one generation")->required();
  gen->add_option("--format", ga->format, "vdb | nvdb | raw | ktx2 | atlas-png | atlas-exr (default: from each extension)");
  gen->add_option("--seed", ga->seed, "Override the preset's seed: an integer in [0, 2^53]");
  gen->add_option("--up", ga->up, "VDB up axis: z (Blender, default) or y (Houdini, Maya); = --set export.vdb.up=...");
  gen->add_option("--resolution", ga->resolution, "Rescale so the longest axis has N voxels (world size kept)");
  gen->add_option("--threads", ga->threads, "Worker threads (0 = all cores); output bytes are identical for any count")
      ->check(CLI::Range(0, kMaxThreads));
  gen->add_option("--set", ga->sets, "Override a preset key with the same validation, e.g. --set threshold=0.4 "
                                     "--set channels.r.octaves=6 --set resolution=[256,64,256]");
  gen->add_option("--region", ga->region,
                  "Generate only X,Y,Z:W,H,D voxels, each extent >= 1, inside the volume (values equal the full run's)");
  gen->add_option("--max-memory", ga->max_memory, "Refuse presets whose memory estimate exceeds this (default 16G)");
  gen->add_flag("--no-skip", ga->no_skip, "Evaluate noise in empty bricks too (for benchmarks; same output)");
  gen->add_flag("--stats", ga->stats, "Print timing and memory even with --quiet");
  gen->add_flag("--mpi", ga->mpi, "Generate on the ranks of an MPI job (implied under mpirun; docs/scale-out.md)");
  gen->add_flag("-q,--quiet", ga->quiet, "No progress bar or summary");
  gen->add_option("--frames", ga->frames,
                  "Bake frames A:B of the preset's motion into a VDB sequence, -o out/cloud_####.vdb (#### = the frame "
                  "number, Blender's naming); frame F is the volume displaced by the motion at F / fps s (docs/motion.md)");
  gen->add_option("--fps", ga->fps, "Frames per second of --frames (default 24)");
  gen->add_flag("--loop", ga->loop,
                "Snap the motion so frame B + 1 equals frame A: whole flow cycles, and whole tiles of wind "
                "(needs motion.wind_shear = 0; box presets need motion.wind_speed = 0)");
  std::string keys;
  for (const auto& pi : params()) {
    std::string k = pi.pointer.substr(1);
    std::replace(k.begin(), k.end(), '/', '.');
    keys += "  " + k + " (" + pi.range + ", default " + pi.default_value + ")\n";
  }
  gen->footer("Preset keys (docs/presets.md explains each):\n" + keys + "\n" + motion_help());
  gen->callback([ga, &run] { run = [ga] { run_generate(*ga); }; });

  auto vpath = std::make_shared<std::vector<std::string>>();
  auto vsets = std::make_shared<std::vector<std::string>>();
  CLI::App* val = app.add_subcommand("validate", "Check presets; print every problem (exit 1) or nothing (exit 0).");
  val->add_option("preset", *vpath, "Preset file(s) or shipped preset names")->required();
  val->add_option("--set", *vsets, "Overrides, as for generate");
  val->callback([vpath, vsets, &run] {
    run = [vpath, vsets] {
      size_t bad = 0;
      for (const auto& p : *vpath) {
        auto problems = check_preset(resolve_preset(p), *vsets);
        for (const auto& m : problems) std::fprintf(stderr, "%s\n", printable(m).c_str());
        bad += !problems.empty();
        if (problems.empty()) std::printf("%s: ok\n", printable(resolve_preset(p)).c_str());
      }
      if (bad) throw InputError(std::to_string(bad) + " preset(s) have problems");
    };
  });

  auto ipath = std::make_shared<std::vector<std::string>>();
  CLI::App* info = app.add_subcommand("info", "Describe a .vdb, .nvdb, .raw (+ .json) or .ktx2 file: grids, sizes, ranges.");
  info->add_option("file", *ipath, "File(s) written by cloudgen")->required();
  info->callback([ipath, &run] {
    run = [ipath] {
      for (const auto& f : *ipath) std::printf("%s", describe_file(f).c_str());  // escaped inside
    };
  });

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

  add_noise_command(app, run);
  add_phase_command(app, run);
  add_flowmap_command(app, run);
  add_blender_command(app, run);
  add_scale_commands(app, run);

  try {
    wrap_cli_help(app);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints the message (or the help)
    return rc == 0 ? kExitOk : kExitInput;
  }
  try {
    if (run) run();
  } catch (const Cancelled&) {
    std::fprintf(stderr, "\ninterrupted: no output was written or replaced\n");
    return kExitInterrupted;
  } catch (...) {
    const std::exception_ptr e = std::current_exception();
    std::fprintf(stderr, "%s\n", error_message_of(e).c_str());
    return exit_code_of(e);
  }
  if (g_cancel) {
    if (!g_cancel_reported) std::fprintf(stderr, "interrupted\n");
    return 130;
  }
  return 0;
}
