// The farm plan (`cloudgen plan`'s manifest) read as untrusted input, docs/robustness.md "Plans":
// whatever merge or a farm task will use is checked before any tile is read, regenerated or written.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

namespace cloudgen {

/// Parses a plan's text (`path` names it in messages) and checks it: every field has its type; the
/// version is ours (1); resolution and tiles per axis are in range; tile files are plain names in
/// the plan's folder (no "..", no folders, no absolute path), each used once; the tiles' regions
/// lie inside the volume, overlap nowhere and together cover it. Throws InputError naming the
/// tile and field.
nlohmann::json parse_plan(const std::string& text, const std::string& path);

/// Reads digits at `at` (no sign, no spaces) into `v`, at most `max`: false otherwise.
bool parse_whole(const std::string& s, size_t& at, uint64_t max, uint64_t& v);

/// A region "X,Y,Z:W,H,D" in voxels, whole numbers up to kMaxResolution only, so "-1" is refused
/// as typed instead of wrapping to 4294967295.
bool parse_region(const std::string& region, std::array<uint32_t, 3>& lo, std::array<uint32_t, 3>& ext);

}  // namespace cloudgen
