// Camera and sun, the default view of a volume, and the placement of box and layer in the world.
#pragma once
#include <glm/glm.hpp>

#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudviewer {

struct Camera {
  glm::dvec3 eye{0.0, 0.0, -10.0};
  glm::dvec3 target{0.0};
  double fov_y_deg = 60;
};
/// Sun from azimuth (degrees clockwise from north = -z, east = +x) and elevation (degrees).
struct Sun {
  double azimuth_deg = 0, elevation_deg = 35;
  glm::dvec3 direction() const;
};

/// The elevations the window's sun handles (arrows, Shift + drag) keep to: a little below the
/// horizon (dusk light) up to the zenith.
inline constexpr double kSunHandleMinElevation = -10, kSunHandleMaxElevation = 90;

/// The sun toward `dir` (any length > 0, world, y up): the inverse of Sun::direction, azimuth in
/// (-180, 180], elevation clamped to [min_elevation, max_elevation] (the azimuth kept).
Sun sun_toward(const glm::dvec3& dir, double min_elevation = -90, double max_elevation = 90);

/// The unit direction from the eye through the point (x, y) of a width x height window, in the
/// window's coordinates as GLFW reports the cursor (pixels from the top-left corner, continuous:
/// (0, 0) is the top-left corner, (width, height) the bottom-right): the inverse of
/// view_projection, so sun_toward(view_direction(...)) is the sun under the cursor.
glm::dvec3 view_direction(const Camera& cam, int width, int height, double x, double y);

/// Solar declination, degrees, on day `day_of_year` (1 = 1 January), Cooper's formula
/// 23.45 sin(360 (284 + N) / 365): 0 at the equinoxes (N = 81, 264), +-23.45 at the solstices.
double solar_declination_deg(double day_of_year);
/// The sun at local solar time `hours` (12 = solar noon; the hour angle is 15 degrees an hour) on
/// day `day_of_year` at latitude `latitude_deg` (north > 0), in the viewer's convention: -z is
/// north, +x east, so the azimuth is the compass bearing (0 north, 90 east, 180 south, 270 west),
/// in [0, 360). elevation = asin(sin lat sin dec + cos lat cos dec cos H); no refraction, no
/// equation of time. The one formula of render.time_of_day and the window's time-of-day slider.
Sun solar_sun(double latitude_deg, double day_of_year, double hours);

/// Camera framing the whole volume from the side (-z), slightly above its middle.
Camera default_camera(const PreparedVolume& vol, double fov_y_deg, double aspect);
/// Sun behind the viewer (the camera's azimuth seen from the target), 35 degrees up.
Sun default_sun(const Camera& cam);

/// Position given in the volume's unit box (the bench track's "volume" space) in world metres. In
/// layer mode x and z count texture tiles and y runs from the layer bottom (0) to its top (1).
glm::dvec3 volume_space_to_world(const PreparedVolume& vol, const RenderSettings& s, const glm::dvec3& uvw);
/// Layer bottom and top altitudes (m above the ground) after the auto rules.
glm::dvec2 layer_altitudes(const PreparedVolume& vol, const RenderSettings& s);
/// World height of the ground plane after the auto rule.
double ground_height(const PreparedVolume& vol, const RenderSettings& s);
/// The default camera for the settings' mode (layer: below the layer, looking at the horizon).
Camera default_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect);

/// Projection used by both renderers (near 0.5 m, far 1e6 m, OpenGL clip conventions), and the
/// camera-relative view (camera at the origin).
glm::dmat4 view_projection(const Camera& cam, int width, int height);

}  // namespace cloudviewer
