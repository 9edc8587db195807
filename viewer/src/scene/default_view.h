// The viewer's default view of an input: the `view` its preset or file metadata carries (camera,
// fov, sun, render.* settings; command-line flags override it), else a bare volume framed from
// 30 degrees above its long side (cloudgen::frame_box, the framing `cloudgen blender` uses too).
#pragma once
#include "../internal.h"

namespace cloudviewer {

/// Reads the view of `o.input` (a preset's `view` section, or the "view" metadata of a .vdb,
/// texture or sidecar) into o.view and applies it where the command line left things unset:
/// render.* keys first with o.sets re-applied on top, the fov unless `fov_given`, the camera unless
/// --camera. Synthetic inputs and builds without cloudgen have no view. Throws InputError naming
/// the input for a bad view.render key.
void apply_input_view(Options& o, bool fov_given);

/// Default camera when there is no --camera and no view camera: box mode frames the box of the
/// voxels with density > 0 from 30 degrees above its long side so it fills the frame; layer mode
/// keeps default_camera.
Camera default_view_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect);

/// The sun for `cam`: --sun, else render.time_of_day's (solar_sun), else the view's azimuth/elevation,
/// each missing one from default_sun.
Sun default_view_sun(const Options& o, const Camera& cam);

}  // namespace cloudviewer
