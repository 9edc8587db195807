// The window's authoring actions on a preset INPUT, outside the GL thread and testable headless:
// Export (cloudgen's own export, as `cloudgen generate`) and Open in Blender (`cloudgen blender`).
// Save preset as is Session::save_preset_as. Internal.
#pragma once
#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace cloudviewer {

/// The preset `input` with `sets` (KEY=VALUE, as `cloudgen generate --set`) generated and written
/// to `outputs` (formats from their extensions) by cloudgen::export_preset, all files or none;
/// `progress` in [0, 1] from worker threads; `cancel` stops it (cloudgen::Cancelled). Returns the
/// files written. InputError / IoError as cloudgen's.
std::vector<std::string> export_preset_files(const std::string& input, const std::vector<std::string>& sets,
                                             const std::vector<std::string>& outputs,
                                             const std::function<void(double)>& progress = {},
                                             const std::atomic<bool>* cancel = nullptr);

/// The cloudgen program beside this cloudviewer (the same build), else `cloudgen` on the PATH.
std::string cloudgen_program();

/// Runs `cloudgen blender VDB -o BLEND` (a Blender scene of the exported volume, as the viewer
/// frames it) and returns BLEND; Error with the command's output when it fails.
std::string open_in_blender(const std::string& vdb, const std::string& blend);

/// Where the window's Save preset as and Export write by default: INPUT's name with "_edited" in
/// the current folder ("cumulus_edited.json", "cumulus_edited.vdb"), never the shipped folder.
std::string edited_name(const std::string& input, const std::string& extension);

}  // namespace cloudviewer
