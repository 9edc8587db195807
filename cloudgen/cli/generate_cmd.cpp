// `cloudgen generate`: a preset into one volume, exported to every -o file in one batch (or to a VDB
// sequence with --frames, or over MPI ranks with --mpi).
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

#include "cloudgen/budget.h"
#include "cloudgen/cli_parse.h"
#include "cloudgen/export_preset.h"
#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/motion.h"
#include "cloudgen/preset.h"
#include "cloudgen/printable.h"
#include "cloudgen/texture_pack.h"
#include "cloudgen/view.h"
#include "cloudgen/weather_map.h"
#include "commands.h"

namespace cloudgen::cli {
namespace {


void run_generate(const GenerateArgs& a) {
  std::vector<std::string> sets = a.sets;
  if (!a.seed.empty()) sets.push_back("seed=" + std::to_string(parse_uint(a.seed, "--seed", kMaxSeed)));
  if (!a.up.empty()) sets.push_back("export.vdb.up=" + a.up);
  if (!a.lod.empty()) sets.push_back("export.vdb.lod=" + a.lod);  // the table's type and range checks
  const std::string path = resolve_preset_path(a.preset);
  Preset p = load_preset(path, sets);
  if (a.resolution) rescale(p, a.resolution);
  std::string budget_note;
  if (!a.voxel_budget.empty()) {
    if (a.resolution) throw InputError("--voxel-budget and --resolution both set the voxel size: give one of them");
    const BudgetChoice c = choose_for_budget(p, parse_voxel_count(a.voxel_budget, "--voxel-budget", 4096), a.threads);
    rescale(p, c.longest);
    budget_note = std::to_string(c.budget);
    if (!a.quiet) std::fprintf(stderr, "%s\n", describe(c).c_str());
  }
  check_lod_levels(p.export_options.vdb_lod, p.resolution.data());  // before any work: nothing written
  const bool sequence = !a.frames.empty() || !a.fps.empty() || a.loop;
  if (!budget_note.empty() && (sequence || mpi_requested(a.mpi)))
    throw InputError("--voxel-budget works in one process without --frames for now: run it once to see the voxel "
                     "size it prints, then give that with --resolution N");
  const bool pack = !a.texture_pack.empty();
  if (pack && (sequence || mpi_requested(a.mpi) || !a.region.empty()))
    throw InputError("--texture-pack works with a whole volume in one process: leave out --frames, --mpi and --region");
  if (sequence) return run_generate_sequence(p, path, a);
  if (a.outputs.empty() && !pack) throw InputError("-o/--output: give at least one output file (.vdb, .nvdb, .raw, .ktx2, .png, .exr)");
  const bool mpi = mpi_requested(a.mpi);  // ranks hold sparse bricks, not the dense volume
  const uint64_t max_memory = parse_bytes(a.max_memory, "--max-memory");
  GenerateOptions go;
  go.threads = a.threads;
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
  if (mpi) {
    OutputBatch batch;  // claimed up front, as export_preset does
    const std::vector<Format> formats = claim_outputs(p, path, a.outputs, a.format, batch);
    set_export_detail(p, path, formats, go);
    return run_generate_mpi(p, go, a.outputs, formats, a.quiet, a.stats);
  }
  // The one path of a preset to its files (cloudviewer's Export takes it too).
  PresetExport e;
  e.outputs = a.outputs;
  e.format = a.format;
  e.max_memory = max_memory;
  e.max_memory_text = "--max-memory " + a.max_memory;
  // The budget that chose the voxel size travels with the file (the size is the grid's transform).
  if (!budget_note.empty()) e.metadata.push_back({"voxel_budget", budget_note});
  e.before_commit = [] { test_hold("commit"); };
  if (pack) {
    e.claim = [&](OutputBatch& batch) {
      // An absent folder appears whole at the commit (staged beside it), or not at all.
      prepare_texture_pack_dir(a.texture_pack, batch);
      for (const std::string& f : texture_pack_files(a.texture_pack)) batch.claim(f, "the texture pack's " + f);
    };
    e.stage = [&](OutputBatch& batch) {
      if (g_cancel) throw Cancelled();
      stage_texture_pack(make_texture_pack(p, a.threads), a.texture_pack, path, batch);
    };
  }
  const ExportedPreset x = export_preset(p, path, e, go);
  const std::vector<Format>& formats = x.formats;
  const GenerateStats& st = x.stats;
  const double write_s = x.write_seconds;
  const uint64_t voxels = uint64_t(x.dims[0]) * x.dims[1] * x.dims[2];
  if (!a.quiet)
    for (size_t i = 0; i < a.outputs.size(); ++i)
      std::fprintf(stderr, "wrote %s (%s)\n", printable(a.outputs[i]).c_str(), format_name(formats[i]));
  if (!a.quiet && pack) std::fprintf(stderr, "wrote texture pack %s/pack.json\n", printable(a.texture_pack).c_str());
  if (a.outputs.empty()) return;  // a pack alone: no volume was generated
  if (!a.quiet || a.stats) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    std::fprintf(stderr,
                 "%s: %ux%ux%u voxels, %zu active (%.2f%%), bricks %zu (%zu skipped, %zu with detail), "
                 "generate %.3f s, write %.3f s, peak memory %s\n",
                 printable(p.name).c_str(), x.dims[0], x.dims[1], x.dims[2], st.active_voxels,
                 100.0 * st.active_voxels / double(std::max<uint64_t>(1, voxels)), st.bricks, st.bricks_skipped,
                 st.detail_bricks, st.seconds, write_s, human_bytes(uint64_t(ru.ru_maxrss) * 1024).c_str());
  }
  if (g_cancel) {
    std::fprintf(stderr, "interrupted after every output was complete and in place\n");
    g_cancel_reported = true;  // main exits 130 without claiming nothing was written
  }
}

}  // namespace

void add_generate_command(CLI::App& app, std::function<void()>& run) {
  auto ga = std::make_shared<GenerateArgs>();
  CLI::App* gen = app.add_subcommand("generate", "Generate a cloud volume from a preset and export it.");
  gen->add_option("preset", ga->preset, "Preset file, or the name of a shipped preset (see `cloudgen presets`)")->required();
  gen->add_option("-o,--output", ga->outputs, "Output file; repeat for several formats from one generation");
  gen->add_option("--texture-pack", ga->texture_pack,
                  "Also write a game-engine texture pack into this folder: base 128 RGBA8, detail 32^3, curl 128^2, "
                  "weather map, each with mips, as KTX2 and raw, and pack.json (docs/textures.md)");
  gen->add_option("--format", ga->format, "vdb | nvdb | raw | ktx2 | atlas-png | atlas-exr (default: from each extension)");
  gen->add_option("--seed", ga->seed, "Override the preset's seed: an integer in [0, 2^53]");
  gen->add_option("--up", ga->up, "VDB up axis: z (Blender, default) or y (Houdini, Maya); = --set export.vdb.up=...");
  gen->add_option("--lod", ga->lod,
                  "Levels of detail in .vdb outputs: N grids density_level_1 .. density_level_N, each twice as coarse "
                  "(0 = none, the default); = --set export.vdb.lod=N");
  gen->add_option("--resolution", ga->resolution, "Rescale so the longest axis has N voxels (world size kept)");
  gen->add_option("--voxel-budget", ga->voxel_budget,
                  "Choose the voxel size (world size kept) so about this many voxels hold cloud, e.g. 200M "
                  "(M = 1e6); the size is printed and the budget stored in the file");
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
}

}  // namespace cloudgen::cli
