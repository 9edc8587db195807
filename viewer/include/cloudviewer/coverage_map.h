// The layer mode's coverage map (weather map): where clouds are and which type they are. A frame
// in layer mode carries the map it renders with (FrameSetup::coverage).
#pragma once
#include <memory>
#include <vector>

namespace cloudviewer {

/// The procedural coverage map: CV_COVERAGE_MAP_SIZE^2 texels, RG interleaved (coverage, cloud
/// type), tileable fBm; made at its first use and kept.
std::shared_ptr<const std::vector<float>> procedural_coverage_map();

}  // namespace cloudviewer
