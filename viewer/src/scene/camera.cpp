// Camera, sun and placement: default framings, the projection both renderers use, layer altitudes
// and the ground height rules.
#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"

namespace cloudviewer {

glm::dvec3 Sun::direction() const {
  double az = glm::radians(azimuth_deg), el = glm::radians(elevation_deg);
  return glm::dvec3(std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az));
}

Sun sun_toward(const glm::dvec3& dir, double min_elevation, double max_elevation) {
  Sun s;
  const double horizontal = std::hypot(dir.x, dir.z);
  s.azimuth_deg = horizontal > 0 ? glm::degrees(std::atan2(dir.x, -dir.z)) : 0.0;
  s.elevation_deg = std::clamp(glm::degrees(std::atan2(dir.y, horizontal)), min_elevation, max_elevation);
  return s;
}

glm::dvec3 view_direction(const Camera& cam, int width, int height, double x, double y) {
  // Window point -> normalised device coordinates (y up) -> a point on the far plane, seen from
  // the eye at the origin of the camera-relative view.
  const glm::dvec4 ndc(2.0 * x / width - 1.0, 1.0 - 2.0 * y / height, 1.0, 1.0);
  const glm::dvec4 p = glm::inverse(view_projection(cam, width, height)) * ndc;
  return glm::normalize(glm::dvec3(p) / p.w);
}

double solar_declination_deg(double day_of_year) {
  return 23.45 * std::sin(glm::radians(360.0 * (284.0 + day_of_year) / 365.0));
}

Sun solar_sun(double latitude_deg, double day_of_year, double hours) {
  const double lat = glm::radians(latitude_deg), dec = glm::radians(solar_declination_deg(day_of_year));
  const double h = glm::radians(15.0 * (hours - 12.0));  // hour angle: negative in the morning
  const double up = std::sin(lat) * std::sin(dec) + std::cos(lat) * std::cos(dec) * std::cos(h);
  // The sun's direction in local east / north components (times cos elevation).
  const double east = -std::cos(dec) * std::sin(h);
  const double north = std::sin(dec) * std::cos(lat) - std::cos(dec) * std::sin(lat) * std::cos(h);
  Sun s;
  s.elevation_deg = glm::degrees(std::asin(std::clamp(up, -1.0, 1.0)));
  s.azimuth_deg = (east == 0 && north == 0) ? 0.0 : glm::degrees(std::atan2(east, north));
  if (s.azimuth_deg < 0) s.azimuth_deg += 360;
  if (s.azimuth_deg >= 360) s.azimuth_deg -= 360;
  return s;
}

Camera default_camera(const PreparedVolume& vol, double fov_y_deg, double aspect) {
  glm::dvec3 s = vol.size(), c = vol.center();
  double tv = std::tan(glm::radians(fov_y_deg) * 0.5);
  double th = tv * aspect;
  double dist = std::max(0.5 * s.x / th, 0.5 * s.y / tv) * 1.15 + 0.5 * s.z;
  Camera cam;
  cam.fov_y_deg = fov_y_deg;
  cam.target = c;
  cam.eye = c + glm::dvec3(0.0, 0.08 * s.y, -dist);
  return cam;
}

Sun default_sun(const Camera& cam) {
  glm::dvec3 v = cam.eye - cam.target;
  Sun sun;
  sun.azimuth_deg = (v.x == 0 && v.z == 0) ? 0.0 : glm::degrees(std::atan2(v.x, -v.z));
  sun.elevation_deg = 35;
  return sun;
}

double ground_height(const PreparedVolume& vol, const RenderSettings& s) {
  if (!s.ground_height_auto) return s.ground_height;
  return s.mode == PlaceMode::Layer ? 0.0 : std::min(0.0, vol.origin.y);
}

glm::dvec2 layer_altitudes(const PreparedVolume& vol, const RenderSettings& s) {
  double top = s.layer_top > 0 ? s.layer_top : s.layer_bottom + vol.size().y;
  if (top <= s.layer_bottom)
    throw InputError("render.layer_top (" + std::to_string(top) + " m) must be above render.layer_bottom (" +
                     std::to_string(s.layer_bottom) + " m)");
  return glm::dvec2(s.layer_bottom, top);
}

glm::dvec3 volume_space_to_world(const PreparedVolume& vol, const RenderSettings& s, const glm::dvec3& uvw) {
  if (s.mode != PlaceMode::Layer) return vol.origin + uvw * vol.size();
  glm::dvec2 alt = layer_altitudes(vol, s);
  glm::dvec3 size = vol.size();
  return glm::dvec3(uvw.x * size.x, ground_height(vol, s) + alt.x + uvw.y * (alt.y - alt.x), uvw.z * size.z);
}

Camera default_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect) {
  if (s.mode != PlaceMode::Layer) return default_camera(vol, fov_y_deg, aspect);
  glm::dvec2 alt = layer_altitudes(vol, s);
  Camera cam;
  cam.fov_y_deg = fov_y_deg;
  cam.eye = glm::dvec3(0.0, ground_height(vol, s) + 0.4 * alt.x, 0.0);
  cam.target = cam.eye + glm::dvec3(0.0, 0.22, 1.0) * 1000.0;
  return cam;
}

glm::dmat4 view_projection(const Camera& cam, int width, int height) {
  glm::dvec3 dir = cam.target - cam.eye;
  if (glm::length(dir) < 1e-9) dir = glm::dvec3(0, 0, 1);
  dir = glm::normalize(dir);
  glm::dvec3 up = std::abs(dir.y) > 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  glm::dmat4 view = glm::lookAt(glm::dvec3(0.0), dir, up);
  glm::dmat4 proj = glm::perspective(glm::radians(cam.fov_y_deg), double(width) / height, 0.5, 1e6);
  return proj * view;
}

}  // namespace cloudviewer
