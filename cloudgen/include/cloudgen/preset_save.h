// Saving an edited preset (the viewer's "Save preset as"): the preset file with KEY=VALUE edits
// applied, written as JSON under the output rules (cloudgen/output.h: atomic, every write checked,
// the old file byte for byte on failure), never into the shipped presets' folder and never over
// the preset it was read from unless asked.
#pragma once
#include <string>
#include <vector>

namespace cloudgen {

/// The shipped presets' folder: $CLOUDGEN_PRESET_DIR, else the source tree's presets/.
std::string shipped_preset_dir();

/// The JSON text of the preset file `path` with `sets` applied (KEY=VALUE as `cloudgen generate
/// --set` spells them, in order), as it would be saved at `to`: a relative coverage.file or
/// motion.flow_map is rewritten relative to `to`'s folder. Checked as a preset read from `to`;
/// InputError naming the file, key, value and what is allowed otherwise.
std::string edited_preset_text(const std::string& path, const std::vector<std::string>& sets, const std::string& to);

/// Writes edited_preset_text(input, sets, target) to `target` atomically. Refused (InputError,
/// nothing written) when `target` is empty or a folder, lies in shipped_preset_dir(), or is
/// `input` itself and `replace_input` is false. Returns what was written.
std::string save_preset_as(const std::string& input, const std::vector<std::string>& sets, const std::string& target,
                           bool replace_input = false);

}  // namespace cloudgen
