#include "scene/default_view.h"

#include <algorithm>
#include <filesystem>

#include "cloudgen/view.h"
#include "cloudviewer/errors.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/preset.h"
#include "cloudgen/texture_pack.h"
#endif

namespace cloudviewer {
namespace {

glm::dvec3 vec(const cloudgen::Vec3& v) { return glm::dvec3(v[0], v[1], v[2]); }

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
/// The input's view and the centre of the box it is framed on (the camera target when the view
/// gives an eye alone).
bool read_view(const std::string& input, const std::vector<std::string>& preset_sets, cloudgen::View& view,
               glm::dvec3& centre) {
  std::error_code ec;
  if (input.rfind("synthetic:", 0) == 0 || !std::filesystem::is_regular_file(input, ec)) return false;
  std::string ext = std::filesystem::path(input).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".json") {
    try {
      const cloudgen::Preset p = cloudgen::load_preset(input, preset_sets);
      view = p.view;
      centre = vec(p.origin) + 0.5 * glm::dvec3(p.resolution[0], p.resolution[1], p.resolution[2]) * p.voxel_size;
      return true;
    } catch (const cloudgen::Error&) {
      // not a preset: a texture sidecar, read below
    }
  }
  cloudgen::SceneInfo info;
  try {
    // A texture pack's view and box are those of its base texture.
    const std::string base = ext == ".json" ? cloudgen::texture_pack_base(input) : "";
    info = cloudgen::read_scene_info(base.empty() ? input : base);
  } catch (const cloudgen::Error&) {
    return false;  // load_volume reports what is wrong with the file
  }
  try {
    view = cloudgen::view_of_metadata(info.metadata, input);
  } catch (const cloudgen::Error& e) {
    throw InputError(e.what());
  }
  centre = vec(info.origin) + 0.5 * vec(info.size());
  return true;
}
#endif

}  // namespace

void apply_input_view(Options& o, bool fov_given) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  glm::dvec3 centre(0.0);
  if (!read_view(o.input, o.preset_sets, o.view, centre) || o.view.empty()) return;
  RenderSettings s;
  for (const auto& [k, v] : o.view.render) {
    try {
      apply_setting(s, k + "=" + v);
    } catch (const InputError& e) {
      throw InputError(o.input + ": view.render." + k + ": " + e.what());
    }
  }
  for (const std::string& a : o.sets) apply_setting(s, a);
  o.settings = s;
  if (!fov_given && o.view.fov) o.fov = *o.view.fov;
  if (!o.camera && o.view.eye) {
    Camera c;
    c.eye = vec(*o.view.eye);
    c.target = o.view.target ? vec(*o.view.target) : centre;
    c.fov_y_deg = o.fov;
    o.camera = c;
  }
#else
  (void)o, (void)fov_given;
#endif
}

Camera default_view_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect) {
  if (s.mode != PlaceMode::Box) return default_camera(vol, s, fov_y_deg, aspect);
  // The box of the voxels with density > 0: a dense texture (or a preset generated here) then
  // frames like the VDB made from it, which holds only those voxels (cloudgen blender frames that).
  // The nanovdb path's box is already the density grid's active box (no dense copy to scan).
  int lo[3] = {vol.dims[0], vol.dims[1], vol.dims[2]}, hi[3] = {-1, -1, -1};
  for (int z = 0; z < (vol.nano ? 0 : vol.dims[2]); ++z)
    for (int y = 0; y < vol.dims[1]; ++y)
      for (int x = 0; x < vol.dims[0]; ++x)
        if (vol.rgba[((size_t(z) * vol.dims[1] + y) * vol.dims[0] + x) * 4] > 0.f) {
          const int c[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
        }
  if (hi[0] < 0)
    for (int a = 0; a < 3; ++a) lo[a] = 0, hi[a] = vol.dims[a] - 1;  // empty: the whole box
  const glm::dvec3 min = vol.origin + glm::dvec3(lo[0], lo[1], lo[2]) * vol.voxel_size;
  const glm::dvec3 size = glm::dvec3(hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1) * vol.voxel_size;
  const cloudgen::Framing f = cloudgen::frame_box({min.x, min.y, min.z}, {size.x, size.y, size.z}, fov_y_deg, aspect);
  Camera c;
  c.eye = vec(f.eye);
  c.target = vec(f.target);
  c.fov_y_deg = fov_y_deg;
  return c;
}

Sun default_view_sun(const Options& o, const Camera& cam) {
  if (o.sun) return *o.sun;
  const RenderSettings& r = o.settings;
  if (r.time_of_day >= 0) return solar_sun(r.latitude, r.day_of_year, r.time_of_day);
  Sun s = default_sun(cam);
  if (o.view.sun_azimuth) s.azimuth_deg = *o.view.sun_azimuth;
  if (o.view.sun_elevation) s.elevation_deg = *o.view.sun_elevation;
  return s;
}

}  // namespace cloudviewer
