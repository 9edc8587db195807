// The Mie phase table of cloud droplets that render.phase=mie reads: the computed one, or one read
// from a --mie-table file. A frame carries the table it renders with (RenderSettings::mie_table,
// FrameSetup::mie); nothing process-wide changes when a file is read.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cloudviewer {

/// The Mie phase function of cloud droplets per colour channel: Lorenz-Mie (cloudgen::phase, water
/// n = 1.331 / 1.333 / 1.337) at 650, 550 and 450 nm over cloudgen's default droplet population
/// (modified gamma, effective radius 10 um, variance 0.111), `size()` angles over theta = 0..pi,
/// each channel normalised to 1 over the sphere under phase.glsl's log-space interpolation.
struct MiePhaseTable {
  std::vector<float> rgb;  ///< 3 floats per angle: red, green, blue
  uint64_t id = 0;         ///< distinct for every table made, so a GPU copy knows when to upload again
  int size() const { return int(rgb.size() / 3); }
  float at(int i, int channel) const { return rgb[size_t(i) * 3 + size_t(channel)]; }
};
/// The computed droplet table, made at its first use and kept (it takes seconds on a small CPU,
/// so renderers ask for it only for Mie frames).
std::shared_ptr<const MiePhaseTable> computed_mie_table();
/// A table read from a text file (`--mie-table`): '#' comments, then one value per line (uniform
/// over theta = 0..180 degrees), two columns "theta_degrees value" (whitespace) or `cloudgen
/// phase`'s CSV (a header line "angle_deg,r,g,b", then one row per angle, one value per channel);
/// one value is used for all three channels. Angles increasing, covering 0 and 180. Resampled to
/// CV_MIE_TABLE_SIZE angles and each channel normalised to 1 over the sphere. Throws InputError
/// naming the file and line.
std::shared_ptr<const MiePhaseTable> read_mie_table(const std::string& path);

}  // namespace cloudviewer
