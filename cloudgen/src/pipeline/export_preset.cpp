// A preset's volume to its output files (export_preset.h).
#include "cloudgen/export_preset.h"
#include "cloudgen/printable.h"

#include <chrono>

#include "cloudgen/errors.h"
#include "cloudgen/mesh_source.h"
#include "cloudgen/output.h"
#include "cloudgen/view.h"
#include "cloudgen/weather_map.h"

namespace cloudgen {

void set_export_detail(const Preset& p, const std::string& path, const std::vector<Format>& formats, GenerateOptions& go) {
  const ExportOptions& eo = p.export_options;
  go.detail = false;
  for (Format f : formats) go.detail = go.detail || needs_detail(f, eo);
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
}

std::vector<Format> claim_outputs(const Preset& p, const std::string& path, const std::vector<std::string>& outputs,
                                  const std::string& format, OutputBatch& batch) {
  // Every file of every output is claimed before any work: an output that would replace the
  // preset, or a sidecar that would collide with another output, is refused up front.
  batch.protect(path, "the input preset " + path);  // for `cloudgen shape`: the mesh, named so below
  if (p.weather_map) batch.protect(p.weather_map->path, "the preset's weather map " + p.weather_map->path);
  for (const ShapeSource& s : p.shape.sources)
    if (s.mesh) batch.protect(s.mesh->file, "the preset's mesh " + s.mesh->file);
    else if (s.vdb) batch.protect(s.vdb->file, "the preset's vdb source " + s.vdb->file);
  std::vector<Format> formats;
  for (const auto& o : outputs) {
    formats.push_back(format.empty() ? format_from_path(o) : parse_format(format));
    for (const OutputFile& of : output_files(o, formats.back(), true)) batch.claim(of.path, of.role);
  }
  return formats;
}

ExportedPreset export_preset(const Preset& p, const std::string& path, const PresetExport& e, GenerateOptions go) {
  if (e.outputs.empty() && !e.stage) throw InputError("export " + path + ": no output file given");
  const ExportOptions& eo = p.export_options;
  ExportedPreset r;
  OutputBatch batch;
  r.formats = claim_outputs(p, path, e.outputs, e.format, batch);
  bool detail = false;
  for (Format f : r.formats) detail |= needs_detail(f, eo);
  if (e.claim) e.claim(batch);
  const uint64_t need = memory_estimate(p, detail);
  if (need > e.max_memory)
    throw InputError(path + ": resolution " + std::to_string(p.resolution[0]) + "x" + std::to_string(p.resolution[1]) + "x" +
                     std::to_string(p.resolution[2]) + " needs about " + human_bytes(need) + ", more than " + e.max_memory_text +
                     " (lower /resolution, use --resolution N or --voxel-budget N, or add --mpi: the sparse path "
                     "holds only the bricks with cloud, in one process too)");
  set_export_detail(p, path, r.formats, go);
  auto cancelled = [&] { return go.cancel && go.cancel->load(); };
  Volume v = e.outputs.empty() ? Volume() : generate(p, go, &r.stats);
  r.dims = v.dims;
  for (const auto& [k, val] : e.metadata) v.metadata.push_back({k, val});
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < e.outputs.size(); ++i) {
    if (cancelled()) throw Cancelled();
    write_volume(v, e.outputs[i], r.formats[i], eo, batch);
  }
  if (e.stage) {
    if (cancelled()) throw Cancelled();
    e.stage(batch);
  }
  if (e.before_commit) e.before_commit();
  if (cancelled()) throw Cancelled();
  batch.commit();
  r.written = e.outputs;
  r.write_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace cloudgen
