// A preset's volume written to its output files: the one code path of `cloudgen generate` (in one
// process, without --frames) and the viewer's "Export" button.
#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"
#include "cloudgen/output.h"
#include "cloudgen/preset.h"

namespace cloudgen {

struct PresetExport {
  std::vector<std::string> outputs;  ///< files; the format from each one's extension unless `format`
  std::string format;                ///< a format name for every output (parse_format), or ""
  /// A resolution needing more memory than this (memory_estimate) is refused before any work.
  uint64_t max_memory = std::numeric_limits<uint64_t>::max();
  std::string max_memory_text = "the memory limit";  ///< how the refusal names the limit ("--max-memory 8G")
  std::vector<std::pair<std::string, std::string>> metadata;  ///< added to the volume's metadata
  std::function<void()> before_commit;  ///< called with every file staged, none published (a test hold)
  /// More files of the same batch (a texture pack's): `claim` runs with the outputs' claims, before
  /// any work; `stage` after the outputs are staged, before the commit. With `stage`, `outputs` may
  /// be empty (then no volume is generated).
  std::function<void(OutputBatch&)> claim, stage;
};

struct ExportedPreset {
  std::vector<std::string> written;  ///< the outputs, in order
  std::vector<Format> formats;
  GenerateStats stats;
  std::array<uint32_t, 3> dims{};
  double write_seconds = 0;
};

/// Claims in `batch` every file of `outputs` (each one's format from `format`, or from its
/// extension when empty) and protects the preset `path` and its weather map; returns the formats.
/// Throws InputError for an output that would replace an input or another output.
std::vector<Format> claim_outputs(const Preset& p, const std::string& path, const std::vector<std::string>& outputs,
                                  const std::string& format, OutputBatch& batch);

/// The detail flags of `go` for these outputs of `p` (read from `path`): detail channels only where
/// a format stores them, and only in cloud where a VDB / NanoVDB bakes the erosion.
void set_export_detail(const Preset& p, const std::string& path, const std::vector<Format>& formats, GenerateOptions& go);

/// Generates `p` (read from `path`) with `go` (threads, skip_empty, progress, cancel, region; the
/// detail flags are set here from the outputs) and writes every output in one batch: every file is
/// claimed before any work (an output that would replace the preset or its weather map, or another
/// output, is refused), all are published together at the end or none (cloudgen/output.h).
/// Throws Cancelled when go.cancel is set, InputError / IoError as the writers do.
ExportedPreset export_preset(const Preset& p, const std::string& path, const PresetExport& e, GenerateOptions go);

}  // namespace cloudgen
