// Scale-out commands: `generate` over MPI ranks (the hook run_generate calls), and farm tiles:
// `cloudgen plan` writes a manifest of tiles, each an ordinary `cloudgen generate --region` job,
// `cloudgen tile PLAN --index I` runs tile I of it (the indexed-job form: a Kubernetes Indexed
// Job's JOB_COMPLETION_INDEX, a Deadline or OpenCue frame number), and `cloudgen merge` checks
// the tiles and writes the one-process VDB (`--resume` regenerates exactly the missing or
// damaged ones).
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "cloudgen/exit_codes.h"
#include "cloudgen/input_scope.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/mpi_run.h"
#include "cloudgen/plan.h"
#include "cloudgen/scale.h"
#include "cloudgen/printable.h"
#include "commands.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace cloudgen::cli {
namespace {


ExportOptions export_options(const Preset& p) { return p.export_options; }

/// Whether detail grid c is written for p (what write_vdb writes after `generate`).
std::array<bool, 3> detail_grids(const Preset& p, const ExportOptions& eo) {
  std::array<bool, 3> d{};
  for (int c = 0; c < 3; ++c) d[c] = eo.vdb_detail && p.channels[c + 1].enabled;
  return d;
}

/// The header of the whole volume (what `generate` without --region stamps on its output).
Volume whole_header(const Preset& p) {
  BrickPlan whole;
  whole.dims = p.resolution;
  whole.region_hi = p.resolution;
  return volume_header(p, whole);
}

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.,:/=+") ==
                        std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// ---- plan ----------------------------------------------------------------------------------------

struct PlanArgs {
  std::string preset, tiles = "2,1,2", out;
  std::vector<std::string> sets;
  int64_t seed = -1;
  uint32_t resolution = 0;
  int threads = 0;
};

/// The generation-changing arguments a tile command repeats (and merge re-applies).
std::vector<std::string> tile_args(const std::vector<std::string>& sets, int64_t seed, uint32_t resolution) {
  std::vector<std::string> a;
  for (const auto& s : sets) a.insert(a.end(), {"--set", s});
  if (seed >= 0) a.insert(a.end(), {"--seed", std::to_string(seed)});
  if (resolution) a.insert(a.end(), {"--resolution", std::to_string(resolution)});
  return a;
}

Preset load_with_args(const std::string& path, const std::vector<std::string>& args, const std::string& where) {
  std::vector<std::string> sets;
  uint32_t resolution = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    if (i + 1 >= args.size()) throw InputError(where + ": argument \"" + args[i] + "\" has no value");
    const std::string& k = args[i];
    const std::string& v = args[++i];
    if (k == "--set") sets.push_back(v);
    else if (k == "--seed") sets.push_back("seed=" + v);
    else if (k == "--resolution") {
      size_t at = 0;
      uint64_t n = 0;
      if (!parse_whole(v, at, UINT32_MAX, n) || at != v.size())  // rescale() checks the range
        throw InputError(where + ": --resolution \"" + printable(v) + "\"; allowed: a whole number in [1, " +
                         std::to_string(kMaxResolution) + "]");
      resolution = uint32_t(n);
    }
    else throw InputError(where + ": unknown argument \"" + k + "\" (allowed: --set, --seed, --resolution)");
  }
  Preset p = load_preset(path, sets);
  if (resolution || std::find(args.begin(), args.end(), "--resolution") != args.end()) rescale(p, resolution);
  return p;
}

void run_plan(const PlanArgs& a) {
  if (a.out.empty()) throw InputError("-o/--output: give the manifest file to write, e.g. -o tiles/plan.json");
  uint32_t t[3];
  {  // whole numbers only: "-1,1,1" is refused as typed (sscanf's %u wrapped it to 4294967295)
    size_t at = 0;
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) {
      uint64_t v = 0;
      ok = parse_whole(a.tiles, at, kMaxResolution, v) && v >= 1 && (i == 2 || (at < a.tiles.size() && a.tiles[at++] == ','));
      t[i] = uint32_t(v);
    }
    if (!ok || at != a.tiles.size())
      throw InputError("--tiles: \"" + printable(a.tiles) + "\" should be X,Y,Z (tiles per axis, each a whole number >= 1)");
  }
  // Absolute paths in the commands, so a farm job may start in any folder (of a shared file system).
  const std::string path = fs::absolute(resolve_preset_path(a.preset)).lexically_normal().string();
  const std::vector<std::string> args = tile_args(a.sets, a.seed, a.resolution);
  const Preset p = load_with_args(path, args, "plan");
  GenerateOptions go;
  go.threads = a.threads;
  go.detail = needs_detail(Format::Vdb, export_options(p));
  const BrickPlan plan = plan_bricks(p, go);
  std::array<uint32_t, 3> nb;
  for (int i = 0; i < 3; ++i) {
    nb[i] = (p.resolution[i] + kBrick - 1) / kBrick;
    if (t[i] > nb[i])
      throw InputError("--tiles: " + std::to_string(t[i]) + " tiles along " + "xyz"[i] + " but the volume has only " +
                       std::to_string(nb[i]) + " bricks of " + std::to_string(kBrick) + " voxels there (allowed: 1.." +
                       std::to_string(nb[i]) + ")");
  }
  const fs::path dir = fs::absolute(a.out).lexically_normal().parent_path();
  json tiles = json::array();
  size_t index = 0;
  for (uint32_t tz = 0; tz < t[2]; ++tz)
    for (uint32_t ty = 0; ty < t[1]; ++ty)
      for (uint32_t tx = 0; tx < t[0]; ++tx, ++index) {
        const uint32_t q[3] = {tx, ty, tz};
        std::array<uint32_t, 3> lo, hi;  // brick-aligned, so tiles share no brick
        for (int i = 0; i < 3; ++i) {
          lo[i] = uint32_t(uint64_t(q[i]) * nb[i] / t[i]) * kBrick;
          hi[i] = std::min(p.resolution[i], uint32_t(uint64_t(q[i] + 1) * nb[i] / t[i]) * kBrick);
        }
        double cost = 0;
        size_t bricks = 0;
        for (const PlannedBrick& b : plan.bricks)
          if (b.lo[0] >= lo[0] && b.lo[0] < hi[0] && b.lo[1] >= lo[1] && b.lo[1] < hi[1] && b.lo[2] >= lo[2] && b.lo[2] < hi[2])
            cost += b.cost, ++bricks;
        char name[32];
        std::snprintf(name, sizeof name, "tile_%04zu.vdb", index);
        const std::string region = std::to_string(lo[0]) + "," + std::to_string(lo[1]) + "," + std::to_string(lo[2]) + ":" +
                                   std::to_string(hi[0] - lo[0]) + "," + std::to_string(hi[1] - lo[1]) + "," +
                                   std::to_string(hi[2] - lo[2]);
        std::string cmd = "cloudgen generate " + shell_quote(path) + " --region " + region;
        for (const auto& s : args) cmd += " " + shell_quote(s);
        cmd += " -q -o " + shell_quote((dir / name).string());
        tiles.push_back({{"index", index}, {"file", name}, {"region", region}, {"bricks", bricks},
                         {"expected_cost", cost}, {"command", cmd}});
      }
  json doc = {{"cloudgen_plan", 1},
              {"generator", "cloudgen " CLOUDGEN_VERSION},
              {"preset", path},
              {"args", args},
              {"preset_name", p.name},
              {"preset_hash", preset_hash(p)},
              {"seed", std::to_string(p.seed)},
              {"resolution", p.resolution},
              {"tiles_per_axis", {t[0], t[1], t[2]}},
              {"total_cost", plan.total_cost()},
              {"tiles", tiles}};
  atomic_write(a.out, [&](const std::string& tmp) {
    std::ofstream o(tmp);
    o << doc.dump(2) << "\n";
    if (!o.flush()) throw IoError(a.out + ": write failed");
  });
  std::fprintf(stderr, "wrote %s: %zu tiles of %s; run each tile's \"command\", then `cloudgen merge %s -o OUT.vdb`\n",
               printable(a.out).c_str(), index, printable(p.name).c_str(), printable(a.out).c_str());
}

// ---- merge ---------------------------------------------------------------------------------------

struct MergeArgs {
  std::string plan, out;
  bool resume = false, quiet = false;
  int threads = 0;
};

std::array<uint32_t, 3> region_lo(const std::string& region, std::array<uint32_t, 3>* ext = nullptr) {
  std::array<uint32_t, 3> lo, e;
  if (!parse_region(region, lo, e)) throw InputError("plan: tile region \"" + printable(region) + "\" is not X,Y,Z:W,H,D");
  if (ext) *ext = e;
  return lo;
}

json read_plan(const std::string& path) {
  const std::string text = read_text_input(path, "the plan " + printable(path), path);
  return parse_plan(text, path);
}

/// Why a tile file is not usable, or "" when it is.
std::string tile_problem(const json& tile, const std::string& file, const json& plan, const Preset& p) {
  if (!fs::exists(file)) return "missing";
  if (tile.contains("checksum")) {
    std::string sum;
    try {
      sum = file_checksum(file);
    } catch (const Error& e) {
      return e.what();
    }
    if (sum != tile["checksum"].get<std::string>()) return "damaged (checksum " + sum + " differs from the plan's " + tile["checksum"].get<std::string>() + ")";
  }
  VdbHeader h;
  try {
    h = read_vdb_header(file);
  } catch (const Error& e) {
    return std::string("unreadable: ") + e.what();
  }
  for (const char* k : {"preset_hash", "seed", "generator"}) {
    const std::string want = k == std::string("generator") ? plan["generator"].get<std::string>() : plan[k].get<std::string>();
    if (h.meta(k) != want) return std::string("inconsistent: ") + k + " is \"" + h.meta(k) + "\", the plan has \"" + want + "\"";
  }
  const auto lo = region_lo(tile["region"].get<std::string>());
  for (int a = 0; a < 3; ++a) {
    const double want = p.origin[a] + lo[a] * p.voxel_size;
    if (std::abs(h.origin[a] - want) > 1e-6 * p.voxel_size || std::abs(h.voxel_size - p.voxel_size) > 1e-9 * p.voxel_size)
      return "inconsistent: it covers another region than " + tile["region"].get<std::string>();
  }
  return "";
}

void regenerate_tile(const Preset& p, const json& tile, const std::string& file, int threads) {
  std::array<uint32_t, 3> ext;
  GenerateOptions go;
  go.threads = threads;
  go.region_origin = region_lo(tile["region"].get<std::string>(), &ext);
  go.region_extent = ext;
  const ExportOptions eo = export_options(p);
  go.detail = needs_detail(Format::Vdb, eo);
  go.occupancy = false;
  go.cancel = &g_cancel;
  write_vdb(generate(p, go), file, eo);  // what `cloudgen generate --region ... -o file` writes
}

/// The preset of a plan, as the plan made it: refused when another cloudgen version made the plan
/// or the preset changed since (tiles and merge must generate what the plan planned).
Preset plan_preset(const json& plan, const std::string& path) {
  const std::string version = "cloudgen " CLOUDGEN_VERSION;
  if (plan["generator"] != version)
    throw InputError(path + ": made by " +
                     (plan["generator"].is_string() ? plan["generator"].get<std::string>() : plan["generator"].dump()) +
                     ", this is " + version +
                     " (outputs could differ: make a new plan)");
  const Preset p = load_with_args(plan["preset"].get<std::string>(), plan["args"].get<std::vector<std::string>>(), path);
  if (preset_hash(p) != plan["preset_hash"].get<std::string>())
    throw InputError(path + ": preset " + plan["preset"].get<std::string>() + " changed since the plan was made (hash " +
                     preset_hash(p) + ", plan " + plan["preset_hash"].get<std::string>() + "): make a new plan");
  if (plan["resolution"] != json(p.resolution))
    throw InputError(path + ": \"resolution\" " + json_excerpt(plan["resolution"]) + " is not the preset's " +
                     json(p.resolution).dump() + " (the plan was edited): make a new plan");
  return p;
}

void run_merge(const MergeArgs& a) {
  if (a.out.empty()) throw InputError("-o/--output: give the merged .vdb to write");
  if (format_from_path(a.out) != Format::Vdb) throw InputError("-o " + a.out + ": merge writes OpenVDB (.vdb) only");
  json plan = read_plan(a.plan);
  const Preset p = plan_preset(plan, a.plan);
  const fs::path dir = fs::path(a.plan).parent_path();
  json& tiles = plan["tiles"];
  auto file_of = [&](const json& t) { return (dir / t["file"].get<std::string>()).string(); };
  auto name_of = [&](const json& t) { return "tile " + std::to_string(t["index"].get<size_t>()) + " (" + file_of(t) + ")"; };
  // The merged file may replace neither the plan nor a tile (by path, or by inode where it exists):
  // refused before any tile is read or regenerated.
  auto same_file = [&](const std::string& f) {
    struct stat s1, s2;
    if (::stat(a.out.c_str(), &s1) == 0 && ::stat(f.c_str(), &s2) == 0) return s1.st_dev == s2.st_dev && s1.st_ino == s2.st_ino;
    return file_identity(f) == file_identity(a.out);
  };
  if (same_file(a.plan)) throw InputError("-o " + a.out + ": would overwrite the plan " + a.plan + "; choose another output name");
  for (const json& t : tiles)
    if (same_file(file_of(t))) throw InputError("-o " + a.out + ": would overwrite " + name_of(t) + "; choose another output name");

  std::vector<bool> regenerated(tiles.size(), false);
  auto regenerate = [&](size_t i, const std::string& why) {
    if (!a.quiet) std::fprintf(stderr, "regenerating %s: %s\n", name_of(tiles[i]).c_str(), why.c_str());
    release_input(file_of(tiles[i]));  // read for its checksum; merge owns it and writes it anew
    regenerate_tile(p, tiles[i], file_of(tiles[i]), a.threads);
    regenerated[i] = true;
  };
  // Every tile checked before anything is written; --resume regenerates exactly the bad ones.
  std::string bad;
  size_t nbad = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    const std::string why = tile_problem(tiles[i], file_of(tiles[i]), plan, p);
    if (why.empty()) continue;
    if (a.resume) {
      regenerate(i, why);
      const std::string again = tile_problem(tiles[i], file_of(tiles[i]), plan, p);
      if (!again.empty()) throw IoError(name_of(tiles[i]) + ": still not usable after regenerating: " + again);
    } else {
      bad += "\n  " + name_of(tiles[i]) + ": " + why + "\n    regenerate with: " + tiles[i]["command"].get<std::string>();
      ++nbad;
    }
  }
  if (nbad)
    throw InputError(a.plan + ": " + std::to_string(nbad) + " of " + std::to_string(tiles.size()) +
                     " tiles are not usable, no output written:" + bad + "\n  (or rerun merge with --resume)");

  const ExportOptions eo = export_options(p);
  for (;;) {  // a tile that fails while being read is regenerated (with --resume) and the merge restarts
    VdbAssembler out(whole_header(p), detail_grids(p, eo), eo);
    size_t failed = tiles.size();
    std::string failure;
    for (size_t i = 0; i < tiles.size(); ++i) {
      if (g_cancel) throw Cancelled();
      try {
        out.add_vdb(file_of(tiles[i]), region_lo(tiles[i]["region"].get<std::string>()));
      } catch (const InputError& e) {
        failed = i, failure = e.what();
        break;
      }
    }
    if (failed < tiles.size()) {
      if (!a.resume || regenerated[failed])
        throw InputError(name_of(tiles[failed]) + ": " + failure + "; no output written" +
                         (a.resume ? "" : " (rerun merge with --resume to regenerate it)"));
      regenerate(failed, failure);
      continue;
    }
    out.write(a.out);
    if (!a.quiet)
      std::fprintf(stderr, "wrote %s from %zu tiles (%llu active density voxels)\n", printable(a.out).c_str(), tiles.size(),
                   static_cast<unsigned long long>(out.active_voxels()));
    break;
  }
  // Record each tile's checksum so a later merge notices a tile damaged or replaced since.
  for (auto& t : tiles) t["checksum"] = file_checksum(file_of(t));
  release_input(a.plan);  // the plan is merge's own record: it is read, then updated with the checksums
  atomic_write(a.plan, [&](const std::string& tmp) {
    std::ofstream o(tmp);
    o << plan.dump(2) << "\n";
    if (!o.flush()) throw IoError(a.plan + ": write failed");
  });
}

// ---- tile ----------------------------------------------------------------------------------------

struct TileArgs {
  std::string plan, index;  // index as text: parsed here, with the plan's range in the message
  bool quiet = false;
  int threads = 0;
};

/// The tile to run: --index, else $JOB_COMPLETION_INDEX (set by a Kubernetes Indexed Job), an
/// integer in [0, count).
size_t tile_index(const TileArgs& a, size_t count, const std::string& plan) {
  const std::string allowed = "allowed: integer in [0, " + std::to_string(count - 1) + "] (" + plan + " has " +
                              std::to_string(count) + " tiles)";
  std::string text, where = "--index";
  if (!a.index.empty()) {
    text = a.index;
  } else if (const char* e = std::getenv("JOB_COMPLETION_INDEX")) {
    text = e, where = "JOB_COMPLETION_INDEX";
  } else {
    throw InputError("--index: give the tile to run, or set JOB_COMPLETION_INDEX (a Kubernetes Indexed Job sets it); " +
                     allowed);
  }
  const bool digits = !text.empty() && text.size() <= 18 && text.find_first_not_of("0123456789") == std::string::npos;
  if (!digits || std::stoull(text) >= count)
    throw InputError(where + ": \"" + printable(text) + "\" is out of range; " + allowed);
  return size_t(std::stoull(text));
}

void run_tile(const TileArgs& a) {
  const json plan = read_plan(a.plan);  // version, tiles and plain file names checked (cloudgen/plan.h)
  const Preset p = plan_preset(plan, a.plan);
  const json& tiles = plan["tiles"];
  const size_t i = tile_index(a, tiles.size(), a.plan);
  const json& tile = tiles[i];
  const std::string file = (fs::path(a.plan).parent_path() / tile["file"].get<std::string>()).string();
  regenerate_tile(p, tile, file, a.threads);  // merge --resume's, i.e. the tile's own command
  if (!a.quiet)
    std::fprintf(stderr, "wrote %s (tile %zu of %zu, region %s)\n", printable(file).c_str(), i, tiles.size(),
                 tile["region"].get<std::string>().c_str());
}

}  // namespace

bool mpi_requested(bool flag) { return flag || mpi::launcher_size() > 0; }

void run_generate_mpi(const Preset& p, const GenerateOptions& go, const std::vector<std::string>& outputs,
                      const std::vector<Format>& formats, bool quiet, bool stats) {
  if (!mpi::built_with_mpi() && mpi::launcher_size() > 1)
    throw InputError("started by an MPI launcher with " + std::to_string(mpi::launcher_size()) +
                     " ranks, but this cloudgen was built without MPI (install openmpi-bin and libopenmpi-dev, "
                     "then rebuild); every rank would write the same file");
  for (size_t i = 0; i < outputs.size(); ++i)
    if (formats[i] != Format::Vdb)
      throw InputError("-o " + outputs[i] + ": with MPI only .vdb outputs are written (" + format_name(formats[i]) +
                       " needs the whole volume densely on one machine; convert the VDB afterwards)");
  mpi::init();
  mpi::Result r;
  try {
    r = mpi::generate_vdb(p, go, export_options(p), outputs);
  } catch (...) {
    // One rank failing alone would leave the others waiting: end the whole job.
    const std::exception_ptr e = std::current_exception();
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& x) {
      std::fprintf(stderr, "error: %s\n", x.what());
    }
    std::fflush(stderr);
    mpi::abort(exit_code_of(e));
  }
  if (r.rank == 0) {
    if (!quiet)
      for (const auto& o : outputs) std::fprintf(stderr, "wrote %s (vdb)\n", printable(o).c_str());
    if (!quiet || stats) {
      size_t bricks = 0;
      for (const auto& s : r.per_rank) bricks += s.gen.bricks;
      std::fprintf(stderr, "%s: %ux%ux%u voxels, %llu active, %zu bricks on %d ranks; plan %.3f s, generate+gather %.3f s, write %.3f s\n",
                   p.name.c_str(), p.resolution[0], p.resolution[1], p.resolution[2],
                   static_cast<unsigned long long>(r.active_voxels), bricks, r.ranks, r.plan_seconds,
                   r.gather_seconds, r.write_seconds);
      // Measured cost of each kind of brick (thread time per brick), the inputs of the scaling
      // model in docs/scale-out.md.
      std::array<size_t, kBrickWorkKinds> kn{};
      std::array<double, kBrickWorkKinds> ks{};
      for (const auto& s : r.per_rank)
        for (int k = 0; k < kBrickWorkKinds; ++k) kn[k] += s.gen.work_bricks[k], ks[k] += s.gen.work_seconds[k];
      const char* kind_names[kBrickWorkKinds] = {"bound-skipped", "detail only", "evaluated, empty", "with cloud"};
      std::string costs;
      for (int k = 0; k < kBrickWorkKinds; ++k) {
        char one[96];
        std::snprintf(one, sizeof one, "%s%s %zu x %.3f ms", k ? ", " : "", kind_names[k], kn[k],
                      kn[k] ? 1e3 * ks[k] / double(kn[k]) : 0.0);
        costs += one;
      }
      std::fprintf(stderr, "  bricks by kind (count x thread time each): %s\n", costs.c_str());
      std::fprintf(stderr, "  gather: rank 0 received %s of brick buffers, added bricks to the grids in %.3f s\n",
                   human_bytes(r.received_bytes).c_str(), r.insert_seconds);
      for (size_t i = 0; i < r.per_rank.size(); ++i) {
        const auto& s = r.per_rank[i];
        std::fprintf(stderr,
                     "  rank %zu: %zu bricks (%zu skipped, %zu with detail, %zu with cloud), generate %.3f s, "
                     "%s %zu bricks, peak memory %s\n",
                     i, s.gen.bricks, s.gen.bricks_skipped, s.gen.detail_bricks,
                     s.gen.work_bricks[int(BrickWork::Cloud)], s.gen.seconds, i == 0 ? "kept" : "sent", s.sent_bricks,
                     human_bytes(s.peak_rss).c_str());
      }
    }
  }
  mpi::finalize();
}

void add_scale_commands(CLI::App& app, std::function<void()>& run) {
  auto pa = std::make_shared<PlanArgs>();
  CLI::App* plan = app.add_subcommand("plan", "Split a preset into farm tiles: a manifest with each tile's command.");
  plan->add_option("preset", pa->preset, "Preset file or shipped preset name")->required();
  plan->add_option("--tiles", pa->tiles, "Tiles per axis X,Y,Z (brick-aligned; default 2,1,2)");
  plan->add_option("-o,--output", pa->out, "Manifest to write (tiles are written beside it)")->required();
  plan->add_option("--set", pa->sets, "Preset overrides, as for generate (repeated in every tile's command)");
  plan->add_option("--seed", pa->seed, "Override the preset's seed");
  plan->add_option("--resolution", pa->resolution, "Rescale so the longest axis has N voxels");
  plan->add_option("--threads", pa->threads, "Threads for the planning bound (0 = all cores)");
  plan->footer("Each tile is an ordinary `cloudgen generate PRESET --region ... -o tile_NNNN.vdb`; run them on any\n"
               "machines, then `cloudgen merge plan.json -o OUT.vdb` writes the one-process VDB.");
  plan->callback([pa, &run] { run = [pa] { run_plan(*pa); }; });

  auto ta = std::make_shared<TileArgs>();
  CLI::App* tile = app.add_subcommand("tile", "Run tile I of a plan: the command an indexed farm job gives each task.");
  tile->add_option("plan", ta->plan, "Manifest written by `cloudgen plan`")->required();
  tile->add_option("--index", ta->index,
                   "Tile to run, 0 to the plan's tile count - 1 (default: $JOB_COMPLETION_INDEX, which a Kubernetes "
                   "Indexed Job sets)");
  tile->add_option("--threads", ta->threads, "Threads (0 = all cores)");
  tile->add_flag("-q,--quiet", ta->quiet, "No messages");
  tile->footer("Writes the tile's file beside the plan, the same bytes as its \"command\"; then\n"
               "`cloudgen merge PLAN -o OUT.vdb` (docs/scale-out.md has a Kubernetes Indexed Job manifest).");
  tile->callback([ta, &run] { run = [ta] { run_tile(*ta); }; });

  auto ma = std::make_shared<MergeArgs>();
  CLI::App* merge = app.add_subcommand("merge", "Check a plan's tiles and merge them into the one-process VDB.");
  merge->add_option("plan", ma->plan, "Manifest written by `cloudgen plan`")->required();
  merge->add_option("-o,--output", ma->out, "Merged .vdb to write")->required();
  merge->add_flag("--resume", ma->resume, "Regenerate (here) exactly the tiles that are missing or damaged, then merge");
  merge->add_option("--threads", ma->threads, "Threads for regenerated tiles (0 = all cores)");
  merge->add_flag("-q,--quiet", ma->quiet, "No messages");
  merge->callback([ma, &run] { run = [ma] { run_merge(*ma); }; });
}

}  // namespace cloudgen::cli
