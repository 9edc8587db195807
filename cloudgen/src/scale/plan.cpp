// The farm plan as untrusted input: cloudgen/plan.h.
#include "cloudgen/plan.h"

#include <cctype>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "cloudgen/errors.h"
#include "cloudgen/generate.h"
#include "cloudgen/json_checked.h"
#include "cloudgen/preset.h"
#include "cloudgen/printable.h"

namespace cloudgen {

using json = nlohmann::json;

bool parse_whole(const std::string& s, size_t& at, uint64_t max, uint64_t& v) {
  if (at >= s.size() || !std::isdigit(static_cast<unsigned char>(s[at]))) return false;
  for (v = 0; at < s.size() && std::isdigit(static_cast<unsigned char>(s[at]));)
    if ((v = v * 10 + uint64_t(s[at++] - '0')) > max) return false;
  return true;
}

bool parse_region(const std::string& region, std::array<uint32_t, 3>& lo, std::array<uint32_t, 3>& ext) {
  uint64_t v[6];
  size_t at = 0;
  for (int i = 0; i < 6; ++i) {
    if (!parse_whole(region, at, kMaxResolution, v[i])) return false;
    if (i < 5 && (at >= region.size() || region[at++] != (i == 2 ? ':' : ','))) return false;
  }
  if (at != region.size()) return false;
  lo = {uint32_t(v[0]), uint32_t(v[1]), uint32_t(v[2])};
  ext = {uint32_t(v[3]), uint32_t(v[4]), uint32_t(v[5])};
  return true;
}

namespace {

/// The checks of parse_plan (cloudgen/plan.h), in the order a reader of the file would look.
void check_plan(const json& doc, const std::string& path) {
  const std::string where = printable(path);
  auto bad = [&](const std::string& what) { return InputError(where + ": " + what); };
  auto need = [&](const json& obj, const char* k, bool (json::*is)() const noexcept, const char* type,
                  const std::string& in) -> const json& {
    if (!obj.is_object() || !obj.contains(k)) throw bad(in + "no \"" + k + "\" (not a plan written by `cloudgen plan`)");
    const json& v = obj[k];
    if (!(v.*is)()) throw bad(in + "\"" + k + "\" is " + json_excerpt(v) + ", not " + type);
    return v;
  };
  if (!doc.is_object()) throw bad("not a plan written by `cloudgen plan` (not a JSON object)");
  const json& version = need(doc, "cloudgen_plan", &json::is_number_unsigned, "a version number", "");
  if (version.get<uint64_t>() != 1)
    throw bad("plan version " + json_excerpt(version) + "; this cloudgen reads version 1 (make a new plan)");
  for (const char* k : {"generator", "preset", "preset_hash", "seed"}) need(doc, k, &json::is_string, "a string", "");
  for (const json& a : need(doc, "args", &json::is_array, "a list", ""))
    if (!a.is_string()) throw bad("\"args\" holds " + json_excerpt(a) + ", not a string");
  std::array<uint64_t, 3> res{}, per{};
  for (auto [key, out, hi] : {std::tuple{"resolution", &res, uint64_t(kMaxResolution)},
                              std::tuple{"tiles_per_axis", &per, uint64_t(kMaxResolution / kBrick)}}) {
    const json& v = need(doc, key, &json::is_array, "a list of 3 whole numbers", "");
    for (size_t i = 0; i < 3; ++i) {
      if (v.size() != 3 || !v[i].is_number_unsigned() || v[i].get<uint64_t>() < 1 || v[i].get<uint64_t>() > hi)
        throw bad("\"" + std::string(key) + "\" is " + json_excerpt(v) + "; allowed: 3 whole numbers in [1, " +
                  std::to_string(hi) + "]");
      (*out)[i] = v[i].get<uint64_t>();
    }
  }
  const json& tiles = need(doc, "tiles", &json::is_array, "a list", "");
  const uint64_t count = per[0] * per[1] * per[2];
  if (tiles.size() != count)
    throw bad(std::to_string(tiles.size()) + " tiles listed, but \"tiles_per_axis\" " + json_excerpt(doc["tiles_per_axis"]) +
              " makes " + std::to_string(count) + ": the plan cannot account for the whole volume");
  std::set<std::string> files;
  std::vector<std::pair<std::array<uint32_t, 3>, std::array<uint32_t, 3>>> boxes;
  uint64_t covered = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    const std::string in = "tile " + std::to_string(i) + ": ";
    const json& t = tiles[i];
    if (need(t, "index", &json::is_number_unsigned, "a whole number", in).get<uint64_t>() != i)
      throw bad(in + "\"index\" is " + json_excerpt(t["index"]) + ", expected " + std::to_string(i));
    const std::string file = need(t, "file", &json::is_string, "a file name", in).get<std::string>();
    need(t, "region", &json::is_string, "a region X,Y,Z:W,H,D", in);
    need(t, "command", &json::is_string, "a string", in);
    if (t.contains("checksum") && !t["checksum"].is_string()) throw bad(in + "\"checksum\" is not a string");
    if (file.empty() || file == "." || file == ".." || file.find('/') != std::string::npos ||
        file.find('\0') != std::string::npos)
      throw bad(in + "file \"" + printable(file) +
                "\" is not a plain file name: tiles live in the plan's folder (no folders, no \"..\", no absolute path)");
    if (!files.insert(file).second) throw bad(in + "file \"" + printable(file) + "\" is already another tile's");
    std::array<uint32_t, 3> lo, ext;
    if (!parse_region(t["region"].get<std::string>(), lo, ext))
      throw bad(in + "region \"" + printable(t["region"].get<std::string>()) + "\" is not X,Y,Z:W,H,D (whole numbers)");
    uint64_t vol = 1;
    for (int a = 0; a < 3; ++a) {
      if (ext[a] < 1 || uint64_t(lo[a]) + ext[a] > res[size_t(a)])
        throw bad(in + "region " + t["region"].get<std::string>() + " is not inside the volume " +
                  json_excerpt(doc["resolution"]));
      vol *= ext[a];
    }
    for (size_t j = 0; j < boxes.size(); ++j) {
      bool overlap = true;
      for (int a = 0; a < 3; ++a)
        overlap = overlap && lo[a] < boxes[j].first[a] + boxes[j].second[a] && boxes[j].first[a] < lo[a] + ext[a];
      if (overlap) throw bad(in + "region " + t["region"].get<std::string>() + " overlaps tile " + std::to_string(j) + "'s");
    }
    boxes.push_back({lo, ext});
    covered += vol;
  }
  if (covered != res[0] * res[1] * res[2])
    throw bad("the tiles cover " + std::to_string(covered) + " of the volume's " + std::to_string(res[0] * res[1] * res[2]) +
              " voxels: the plan cannot account for the whole volume");
}

}  // namespace

json parse_plan(const std::string& text, const std::string& path) {
  json doc = parse_json_checked(text, path);  // depth and duplicate keys checked
  check_plan(doc, path);
  return doc;
}

}  // namespace cloudgen
