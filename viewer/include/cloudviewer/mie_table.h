// The Mie phase table of cloud droplets that render.phase=mie reads.
#pragma once
#include <vector>
#include <string>

namespace cloudviewer {

/// The Mie phase function of cloud droplets per colour channel: Lorenz-Mie (cloudgen::phase, water
/// n = 1.331 / 1.333 / 1.337) at 650, 550 and 450 nm over cloudgen's default droplet population
/// (modified gamma, effective radius 10 um, variance 0.111), `size()` angles over theta = 0..pi,
/// each channel normalised to 1 over the sphere under phase.glsl's log-space interpolation.
struct MiePhaseTable {
  std::vector<float> rgb;  ///< 3 floats per angle: red, green, blue
  int size() const { return int(rgb.size() / 3); }
  float at(int i, int channel) const { return rgb[size_t(i) * 3 + size_t(channel)]; }
};
/// The table render.phase=mie reads (the --mie-table file if one was loaded), computed at its
/// first use and cached: ~0.9 s per wavelength on 2 cores, so renderers ask only for Mie frames.
const MiePhaseTable& mie_phase_table();
/// Bumped by every load_mie_table, so a GPU copy knows when to upload the table again.
int mie_table_generation();
/// Replaces the computed Mie table with one read from a text file (`--mie-table`): '#' comments,
/// then one value per line (uniform over theta = 0..180 degrees), two columns "theta_degrees value"
/// (whitespace) or `cloudgen phase`'s CSV (a header line "angle_deg,r,g,b", then one row per angle,
/// one value per channel); one value is used for all three channels. Angles increasing, covering
/// 0 and 180. Resampled to CV_MIE_TABLE_SIZE angles and each channel normalised to 1 over the
/// sphere. An empty path restores the computed table. Throws InputError naming the file and line.
void load_mie_table(const std::string& path);

}  // namespace cloudviewer
