// How a cloud is meant to be seen and lit: a preset's optional `view` section, the physical scale
// every renderer needs (extinction per metre at density 1, phase asymmetry), and the default
// framing of a bare volume. Shared by the VDB writer (metadata), cloudviewer (its default view) and
// `cloudgen blender` (the Cycles scene), so the three agree by construction. Header-only math, no
// OpenVDB, no OpenGL: the viewer includes it even when built without the cloudgen library.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cloudgen {

using Vec3 = std::array<double, 3>;

/// Extinction coefficient per metre at density 1 when render.sigma_t is not set (0 = auto): half
/// an optical depth per voxel edge. The one definition used by the viewer's renderers and the VDB
/// metadata `extinction_per_metre`.
inline double default_extinction_per_metre(double voxel_size) { return 0.5 / voxel_size; }

/// The viewer's lighting constants (cloudviewer's make_frame uses them; test_viewer checks the
/// render-setting defaults against Look below).
inline constexpr Vec3 kSunColor{{1.0, 0.96, 0.9}};
inline constexpr Vec3 kAmbientColor{{0.30, 0.38, 0.52}};
inline constexpr Vec3 kSkyZenith{{0.12, 0.24, 0.55}};
/// Ground albedo colour at render.ground_albedo = 0.18 (the viewer varies it by +-10% over 8 km).
inline constexpr Vec3 kGroundColor{{0.10, 0.12, 0.07}};
/// Elevation of the default sun, which stands behind the viewer.
inline constexpr double kDefaultSunElevation = 35.0;
/// Elevation of the default camera above a bare volume's long side.
inline constexpr double kDefaultViewElevation = 30.0;

/// A preset's `view` section; every member optional (unset = the viewer's default).
struct View {
  std::optional<Vec3> eye, target;  ///< camera, world metres (y up, the preset's frame)
  std::optional<double> fov;        ///< vertical field of view, degrees
  std::optional<double> sun_azimuth, sun_elevation;  ///< degrees (azimuth clockwise from -z)
  /// render.KEY=VALUE assignments for cloudviewer (its --help-params lists the keys), in order.
  std::vector<std::pair<std::string, std::string>> render;
  bool empty() const { return !eye && !target && !fov && !sun_azimuth && !sun_elevation && render.empty(); }
};

/// The `view` as compact JSON (the VDB metadata "view" and texture sidecars carry it).
std::string view_to_json(const View& v);
/// Parses view_to_json's output (or a preset's `view` object). Throws InputError naming `source`.
View view_from_json(const std::string& json_text, const std::string& source);
/// The view stored in a volume's metadata ("view"), or an empty view.
View view_of_metadata(const std::vector<std::pair<std::string, std::string>>& metadata, const std::string& source);

/// Records a non-empty view as the metadata entry "view" (replacing an older one), so every
/// format cloudgen writes carries it.
void add_view_metadata(std::vector<std::pair<std::string, std::string>>& metadata, const View& v);

/// The render settings another renderer needs to light the cloud like the viewer, with the
/// viewer's defaults, after the view's render.* keys (only those below are read here).
struct Look {
  double sigma_t = 0;  ///< 1/m at density 1; 0 = default_extinction_per_metre(voxel size)
  double density = 1;  ///< density multiplier
  double erosion = 0.35;
  double albedo = 1;
  double g = 0.3;  ///< Henyey-Greenstein asymmetry
  double sun_intensity = 30;
  double ambient = 0.8;
  double exposure = 1.5;
  bool ground = true;
  double ground_albedo = 0.18;
  std::string phase = "hg", tonemap = "reinhard";
  /// Extinction per metre at density 1 after the multiplier: what Blender's Principled Volume
  /// Density is set to (the grid holds density in [0, 1]).
  double extinction(double voxel_size) const {
    return (sigma_t > 0 ? sigma_t : default_extinction_per_metre(voxel_size)) * density;
  }
};
/// The Look after `view.render` (numbers parsed; unknown keys ignored here, the viewer checks them).
Look look_of_view(const View& v, const std::string& source);

/// Sun direction (unit, y up) from azimuth (clockwise from -z toward +x) and elevation, degrees.
inline Vec3 sun_direction(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * M_PI / 180, el = elevation_deg * M_PI / 180;
  return {std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az)};
}
/// Azimuth of the default sun: behind the camera (the camera's azimuth seen from the target).
inline double sun_azimuth_behind(const Vec3& eye, const Vec3& target) {
  const double x = eye[0] - target[0], z = eye[2] - target[2];
  return (x == 0 && z == 0) ? 0.0 : std::atan2(x, -z) * 180 / M_PI;
}

struct Framing {
  Vec3 eye, target;
};
/// Frames the box [lo, lo + size] (y up) from `elevation_deg` above the middle of its long
/// horizontal side, at the distance where its eight corners just fill `fill` of the frame.
inline Framing frame_box(const Vec3& lo, const Vec3& size, double fov_y_deg, double aspect,
                         double elevation_deg = kDefaultViewElevation, double fill = 0.92) {
  const Vec3 c{lo[0] + 0.5 * size[0], lo[1] + 0.5 * size[1], lo[2] + 0.5 * size[2]};
  const double el = elevation_deg * M_PI / 180;
  // Look across the short horizontal axis, so the long side faces the camera: from -z when x is
  // the long axis (the viewer's classic side view), else from -x.
  const bool along_x = size[0] >= size[2];
  const Vec3 h = along_x ? Vec3{0, 0, 1} : Vec3{1, 0, 0};                       // horizontal forward
  const Vec3 fwd{h[0] * std::cos(el), -std::sin(el), h[2] * std::cos(el)};      // looking down
  const Vec3 right = along_x ? Vec3{-1, 0, 0} : Vec3{0, 0, 1};                   // fwd x up (y)
  const Vec3 up{right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
                right[0] * fwd[1] - right[1] * fwd[0]};
  const double tv = std::tan(fov_y_deg * M_PI / 360) * fill, th = tv * aspect;
  double dist = 0;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p{((i & 1) - 0.5) * size[0], (((i >> 1) & 1) - 0.5) * size[1], (((i >> 2) & 1) - 0.5) * size[2]};
    auto dot = [&](const Vec3& a) { return a[0] * p[0] + a[1] * p[1] + a[2] * p[2]; };
    // Depth along fwd is dist + dot(fwd); the corner fits when |x| <= th * depth and |y| <= tv * depth.
    dist = std::max({dist, std::abs(dot(right)) / th - dot(fwd), std::abs(dot(up)) / tv - dot(fwd)});
  }
  return {{c[0] - dist * fwd[0], c[1] - dist * fwd[1], c[2] - dist * fwd[2]}, c};
}

/// What a cloudgen file says about its placement and look without loading its voxels: the
/// density's active box in the y-up frame (as read_volume would place it) and the metadata.
struct SceneInfo {
  Vec3 origin{{0, 0, 0}};  ///< min corner of the active box, metres, y up
  std::array<uint32_t, 3> dims{{0, 0, 0}};
  double voxel_size = 1;
  char up = 'y';  ///< the file's up axis: 'y' or 'z'
  uint32_t lod_levels = 0;  ///< .vdb levels of detail (grids density_level_1 .. _N; read_vdb_level)
  std::vector<std::pair<std::string, std::string>> metadata;
  Vec3 size() const { return {dims[0] * voxel_size, dims[1] * voxel_size, dims[2] * voxel_size}; }
};
/// A .vdb's header (grid metadata only, no voxels); other formats are read in full.
SceneInfo read_scene_info(const std::string& path);
SceneInfo read_vdb_scene_info(const std::string& path);

}  // namespace cloudgen
