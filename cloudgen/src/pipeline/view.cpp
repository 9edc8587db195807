// The `view` section's JSON form, the Look it implies, and SceneInfo for non-VDB files.
#include "cloudgen/view.h"
#include "cloudgen/nvdb.h"

#include <nlohmann/json.hpp>

#include "cloudgen/volume.h"

namespace cloudgen {
namespace {
using json = nlohmann::json;

double number_of(const std::string& key, const std::string& value, const std::string& source) {
  try {
    size_t used = 0;
    double d = std::stod(value, &used);
    if (used == value.size() && std::isfinite(d)) return d;
  } catch (const std::exception&) {
  }
  throw InputError(source + ": view.render." + key + ": \"" + value + "\" is not a number");
}
}  // namespace

std::string view_to_json(const View& v) {
  json j = json::object();
  if (v.eye) j["eye"] = *v.eye;
  if (v.target) j["target"] = *v.target;
  if (v.fov) j["fov"] = *v.fov;
  if (v.sun_azimuth) j["sun"]["azimuth"] = *v.sun_azimuth;
  if (v.sun_elevation) j["sun"]["elevation"] = *v.sun_elevation;
  if (!v.render.empty()) {
    json r = json::object();
    for (auto& [k, val] : v.render) r[k] = val;
    j["render"] = r;
  }
  return j.dump();
}

View view_from_json(const std::string& text, const std::string& source) {
  View v;
  try {
    json j = json::parse(text);
    if (!j.is_object()) throw InputError(source + ": view: expected a JSON object");
    auto vec3 = [](const json& a) { return Vec3{a.at(0).get<double>(), a.at(1).get<double>(), a.at(2).get<double>()}; };
    if (j.contains("eye")) v.eye = vec3(j["eye"]);
    if (j.contains("target")) v.target = vec3(j["target"]);
    if (j.contains("fov")) v.fov = j["fov"].get<double>();
    if (j.contains("sun")) {
      if (j["sun"].contains("azimuth")) v.sun_azimuth = j["sun"]["azimuth"].get<double>();
      if (j["sun"].contains("elevation")) v.sun_elevation = j["sun"]["elevation"].get<double>();
    }
    if (j.contains("render"))
      for (auto& [k, val] : j["render"].items()) v.render.push_back({k, val.is_string() ? val.get<std::string>() : val.dump()});
  } catch (const json::exception& e) {
    throw InputError(source + ": view metadata is not valid: " + e.what());
  }
  return v;
}

View view_of_metadata(const std::vector<std::pair<std::string, std::string>>& metadata, const std::string& source) {
  for (auto& [k, val] : metadata)
    if (k == "view") return view_from_json(val, source);
  return {};
}

void add_view_metadata(std::vector<std::pair<std::string, std::string>>& metadata, const View& v) {
  metadata.erase(std::remove_if(metadata.begin(), metadata.end(), [](const auto& kv) { return kv.first == "view"; }),
                 metadata.end());
  if (!v.empty()) metadata.push_back({"view", view_to_json(v)});
}

Look look_of_view(const View& v, const std::string& source) {
  Look l;
  for (const auto& kv : v.render) {
    const std::string& k = kv.first;  // a structured binding cannot be captured in C++17 (clang refuses)
    auto num = [&] { return number_of(k, kv.second, source); };
    if (k == "sigma_t") l.sigma_t = num();
    else if (k == "density") l.density = num();
    else if (k == "erosion") l.erosion = num();
    else if (k == "albedo") l.albedo = num();
    else if (k == "g") l.g = num();
    else if (k == "sun_intensity") l.sun_intensity = num();
    else if (k == "ambient") l.ambient = num();
    else if (k == "exposure") l.exposure = num();
    else if (k == "ground_albedo") l.ground_albedo = num();
    else if (k == "ground") l.ground = kv.second == "true" || kv.second == "1";
    else if (k == "phase") l.phase = kv.second;
    else if (k == "tonemap") l.tonemap = kv.second;
  }
  return l;
}

SceneInfo read_scene_info(const std::string& path) {
  const std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  if (ext == ".vdb" || ext == ".VDB") return read_vdb_scene_info(path);
  if (path.size() >= 5 && (path.substr(path.size() - 5) == ".nvdb" || path.substr(path.size() - 5) == ".NVDB")) {
    const NanoVolume n = read_nvdb(path);  // sparse: no dense copy for the view
    SceneInfo s;
    s.dims = n.dims;
    s.voxel_size = n.voxel_size;
    s.origin = n.origin;
    s.metadata = n.metadata;
    s.up = n.up;
    return s;
  }
  Volume v = read_volume(path);
  SceneInfo s;
  s.dims = v.dims;
  s.voxel_size = v.voxel_size;
  s.origin = v.origin;
  s.metadata = v.metadata;
  return s;
}

}  // namespace cloudgen
