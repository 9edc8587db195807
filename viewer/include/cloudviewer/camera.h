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
