// Save an edited preset (preset_save.h).
#include "cloudgen/preset_save.h"

#include <cstdlib>
#include <filesystem>

#include "cloudgen/errors.h"
#include "cloudgen/output.h"
#include "cloudgen/printable.h"

namespace cloudgen {

namespace fs = std::filesystem;

std::string shipped_preset_dir() {
  if (const char* e = std::getenv("CLOUDGEN_PRESET_DIR")) return e;
  return std::string(CLOUD_SOURCE_DIR) + "/presets";
}

std::string save_preset_as(const std::string& input, const std::vector<std::string>& sets, const std::string& target,
                           bool replace_input) {
  const std::string what = "save preset as " + printable(target);
  if (target.empty()) throw InputError("save preset as: no file name given");
  std::error_code ec;
  if (fs::is_directory(target, ec)) throw InputError(what + ": that is a folder; name a .json file in it");
  const std::string id = file_identity(target);
  if (fs::path(id).parent_path() == fs::path(file_identity(shipped_preset_dir())))
    throw InputError(what + ": that is the shipped presets' folder (" + printable(shipped_preset_dir()) +
                     "), which is never written; save the preset elsewhere");
  const bool over_input = id == file_identity(input);
  if (over_input && !replace_input)
    throw InputError(what + ": that is the preset being edited; save it under another name (or ask to replace it)");
  const std::string text = edited_preset_text(input, sets, target);
  if (over_input) release_input(input);  // asked for: the edited preset replaces its file
  atomic_write(target, [&](const std::string& tmp) { write_file_bytes(tmp, text.data(), text.size()); });
  return text;
}

}  // namespace cloudgen
