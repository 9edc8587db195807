// `cloudgen shape`: one mesh to a cloud volume in one command. It writes the preset it would take
// (a mesh source fitted into a volume of the mesh's proportions, the noise of a style) and runs it
// through the one export path of `generate` (export_preset.h); --save-preset keeps that preset to
// edit and regenerate.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "cloudgen/cli_parse.h"
#include "cloudgen/export_preset.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/output.h"
#include "cloudgen/preset.h"
#include "cloudgen/printable.h"
#include "cloudgen/schema.h"
#include "commands.h"

namespace cloudgen::cli {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct ShapeArgs {
  std::string mesh, style = "billowy", seed = "42", up, save_preset, max_memory = "16G", format;
  std::vector<std::string> outputs;
  double size = 2000, voxel_size = 0;
  int threads = 0;
  bool quiet = false;
};

/// The shape modifiers of a style (shape.h ShapeModifier), scaled to the cloud's longest side:
/// billowy lifts cauliflower domes, more toward the top, with a few wisps at the base; wispy erodes
/// curl-advected fibres, more downwind. `base` and `top` are the world heights of the mesh's box.
/// Billowy's billows, a fraction of the cloud's longest side (the volume's margin holds them).
constexpr double kBillowFraction = 0.06;

json style_modifiers(const std::string& style, double size, double base, double top) {
  const double h = top - base;
  json out = json::object();
  if (style == "billowy") {
    json& b = out["billowy"];
    b["amplitude"] = kBillowFraction * size, b["period"] = 0.2 * size, b["octaves"] = 4, b["gain"] = 0.65;
    b["heights"] = json::array({base + 0.1 * h, top});
    json& w = out["wispy"];
    w["amplitude"] = 0.03 * size, w["period"] = 0.1 * size, w["heights"] = json::array({base + 0.35 * h, base});
  } else if (style == "wispy") {
    json& w = out["wispy"];
    w["amplitude"] = 0.06 * size, w["period"] = 0.15 * size, w["octaves"] = 4, w["warp"] = 1.0, w["downwind"] = 0.5;
  }
  return out;
}

/// Margin the style's modifiers need around the mesh: billowy lifts the surface by its amplitude.
double style_lift(const std::string& style, double size) { return style == "billowy" ? kBillowFraction * size : 0.0; }

/// The noise of a style: how much the Perlin-Worley base erodes the fitted shape (threshold,
/// remap) and at which scale (period: cells across the volume).
json style_noise(const std::string& style, json& preset) {
  if (style == "smooth") {
    preset["threshold"] = 0.08;
    return {{"r", {{"kind", "perlin-worley"}, {"period", 3}, {"octaves", 3}, {"worley_octaves", 2}, {"gain", 0.45}, {"remap", {0.55, 0.95}}}}};
  }
  if (style == "billowy") {
    preset["threshold"] = 0.2;
    return {{"r", {{"kind", "perlin-worley"}, {"period", 4}, {"octaves", 4}, {"worley_octaves", 3}, {"gain", 0.5}, {"remap", {0.75, 0.92}}}},
            {"g", {{"enabled", true}, {"kind", "worley"}, {"period", 8}, {"octaves", 3}}},
            {"b", {{"enabled", true}, {"kind", "worley"}, {"period", 16}, {"octaves", 3}}},
            {"a", {{"enabled", true}, {"kind", "worley"}, {"period", 32}, {"octaves", 2}}}};
  }
  if (style == "wispy") {
    preset["threshold"] = 0.32;
    return {{"r", {{"kind", "perlin-worley"}, {"period", 6}, {"octaves", 5}, {"worley_octaves", 4}, {"gain", 0.6}, {"remap", {0.6, 0.95}}}},
            {"g", {{"enabled", true}, {"kind", "worley"}, {"period", 12}, {"octaves", 3}}},
            {"b", {{"enabled", true}, {"kind", "worley"}, {"period", 24}, {"octaves", 3}}},
            {"a", {{"enabled", true}, {"kind", "worley"}, {"period", 48}, {"octaves", 2}}}};
  }
  throw InputError("--style " + printable(style) + ": expected smooth | billowy | wispy");
}

void run_shape(const ShapeArgs& a) {
  if (a.outputs.empty()) throw InputError("-o/--output: give at least one output file (.vdb, .nvdb, .raw, .ktx2, .png, .exr)");
  if (!(a.size >= 10 && a.size <= 1e6))
    throw InputError("--size " + shortest_text(a.size) + ": the cloud's longest side in metres, in [10, 1e6]");
  const double vs = a.voxel_size > 0 ? a.voxel_size : a.size / 128;
  if (!(vs >= a.size / kMaxResolution * 1.0001 && vs <= a.size / 4))
    throw InputError("--voxel-size " + shortest_text(a.voxel_size) + ": for --size " + shortest_text(a.size) +
                     " it must lie in [" + shortest_text(a.size / kMaxResolution * 1.0001) + ", " + shortest_text(a.size / 4) +
                     "] (4 to " + std::to_string(kMaxResolution) + " voxels along the longest side)");
  const uint64_t seed = parse_uint(a.seed, "--seed", kMaxSeed);
  const std::string mesh_path = fs::absolute(a.mesh).lexically_normal().string();
  const TriangleMesh m = read_mesh(mesh_path, "mesh " + printable(a.mesh));
  if (m.open_edges > 0 && !a.quiet)
    std::fprintf(stderr, "warning: %s is not closed (%zu edges with one triangle): it has no inside, so the cloud is a "
                         "sheet along its surface\n", printable(a.mesh).c_str(), m.open_edges);
  // The volume: the mesh's proportions, its longest side `size`, plus the falloff's margin.
  const double longest = std::max({m.hi[0] - m.lo[0], m.hi[1] - m.lo[1], m.hi[2] - m.lo[2]});
  const double falloff = a.size / 10, margin = falloff / 2 + style_lift(a.style, a.size) + 2 * vs;
  std::array<uint32_t, 3> res;
  std::array<double, 3> extent;
  for (int i = 0; i < 3; ++i) {
    const double e = (m.hi[i] - m.lo[i]) / longest * a.size + 2 * margin;
    res[i] = uint32_t(std::max(8.0, std::ceil(e / vs)));
    if (res[i] > kMaxResolution)
      throw InputError("--voxel-size " + shortest_text(vs) + ": the volume would have " + std::to_string(res[i]) +
                       " voxels along an axis, more than " + std::to_string(kMaxResolution));
    extent[i] = res[i] * vs;
  }
  json p;
  p["name"] = fs::path(a.mesh).stem().string();
  p["description"] = "A cloud in the shape of " + fs::path(a.mesh).filename().string() + " (cloudgen shape, style " + a.style + ")";
  p["seed"] = seed;
  p["resolution"] = res;
  p["voxel_size"] = vs;
  p["origin"] = {-extent[0] / 2, 1000.0, -extent[2] / 2};  // the base 1 km up, centred on the origin
  p["tiling"] = false;
  p["channels"] = style_noise(a.style, p);
  p["density_scale"] = 1.0;
  const fs::path preset_at = a.save_preset.empty() ? fs::path(mesh_path) : fs::absolute(a.save_preset);
  const fs::path rel = fs::path(mesh_path).lexically_relative(preset_at.parent_path());
  p["shape"] = {{"falloff", falloff},
                {"sources", {{{"kind", "mesh"}, {"file", a.save_preset.empty() || rel.empty() ? mesh_path : rel.generic_string()},
                              {"fit", true}}}}};
  // The fitted mesh fills the volume less the margin (fit_sources): its box in world heights.
  const json mods = style_modifiers(a.style, a.size, 1000.0 + margin, 1000.0 + extent[1] - margin);
  for (const auto& [k, v] : mods.items()) p["shape"][k] = v;
  p["occupancy"] = {{"cell", 4}, {"padding", 2}};
  // Seen from the front (-z), a little from the side and below the top, the sun from the left.
  const std::array<double, 3> c{0.0, 1000.0 + extent[1] / 2, 0.0};
  const double back = 0.6 * std::max({extent[0], extent[1], extent[2]}) + extent[2] / 2;
  p["view"] = {{"eye", {c[0] + 0.35 * back, c[1] - 0.1 * extent[1], c[2] - 1.5 * back}},
               {"target", c},
               {"fov", 45},
               {"sun", {{"azimuth", 50}, {"elevation", 30}}}};
  if (!a.up.empty()) p["export"]["vdb"]["up"] = a.up;
  const std::string text = p.dump(2) + "\n";
  const std::string source = preset_at.string();
  const Preset preset = parse_preset(text, source);
  PresetExport e;
  e.outputs = a.outputs;
  e.format = a.format;
  e.max_memory = parse_bytes(a.max_memory, "--max-memory");
  e.max_memory_text = "--max-memory " + a.max_memory;
  if (!a.save_preset.empty()) {
    e.claim = [&](OutputBatch& batch) { batch.claim(a.save_preset, "the preset " + printable(a.save_preset)); };
    e.stage = [&](OutputBatch& batch) {
      batch.stage(a.save_preset, [&](const std::string& tmp) { write_file_bytes(tmp, text.data(), text.size()); });
    };
  }
  GenerateOptions go;
  go.threads = a.threads;
  go.cancel = &g_cancel;
  auto bar = progress_bar("shape", a.quiet);
  go.progress = [bar](double f) {
    if (bar) bar(f);
  };
  // The mesh is the input this run protects (the preset, if saved, is one of its outputs).
  const ExportedPreset x = export_preset(preset, mesh_path, e, go);
  if (a.quiet) return;
  for (const std::string& o : x.written) std::fprintf(stderr, "wrote %s\n", printable(o).c_str());
  if (!a.save_preset.empty()) std::fprintf(stderr, "wrote %s (the preset: edit it and run cloudgen generate)\n", printable(a.save_preset).c_str());
  std::fprintf(stderr, "%s: %zu triangles, %ux%ux%u voxels of %s m, %zu active, generate %.3f s\n", printable(a.mesh).c_str(),
               m.triangles.size(), x.dims[0], x.dims[1], x.dims[2], shortest_text(vs).c_str(), x.stats.active_voxels,
               x.stats.seconds);
}

}  // namespace

void add_shape_command(CLI::App& app, std::function<void()>& run) {
  auto a = std::make_shared<ShapeArgs>();
  CLI::App* c = app.add_subcommand("shape", "Turn a mesh (OBJ, PLY, STL, glTF/GLB) into a cloud volume.");
  c->add_option("mesh", a->mesh, "The mesh; closed meshes give a solid cloud, open ones a sheet")->required();
  c->add_option("-o,--output", a->outputs, "Output file (.vdb, .nvdb, .raw, .ktx2, ...); repeat for several")->required();
  c->add_option("--format", a->format, "vdb | nvdb | raw | ktx2 | atlas-png | atlas-exr (default: from each extension)");
  c->add_option("--size", a->size, "The cloud's longest side in metres (default 2000); the mesh's own units are ignored");
  c->add_option("--voxel-size", a->voxel_size, "Voxel edge in metres (default: size / 128)");
  c->add_option("--style", a->style, "smooth | billowy (default: cauliflower domes, more toward the top) | wispy (fibres)");
  c->add_option("--seed", a->seed, "Seed of the noise, an integer in [0, 2^53] (default 42)");
  c->add_option("--up", a->up, "VDB up axis: z (Blender, default) or y (Houdini, Maya)");
  c->add_option("--save-preset", a->save_preset, "Also write the preset used (edit it, then cloudgen generate it)");
  c->add_option("--max-memory", a->max_memory, "Refuse a volume needing more memory than this (default 16G)");
  c->add_option("--threads", a->threads, "Worker threads (0 = all cores); output bytes are identical for any count");
  c->add_flag("-q,--quiet", a->quiet, "No progress or summary");
  c->footer("Example:\n  cloudgen shape bunny.obj -o bunny.vdb --size 1500 --style billowy --save-preset bunny.json\n"
            "  cloudgen blender bunny.vdb -o bunny.blend");
  c->callback([a, &run] { run = [a] { run_shape(*a); }; });
}

}  // namespace cloudgen::cli
