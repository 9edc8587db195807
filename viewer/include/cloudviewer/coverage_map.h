// The layer mode's coverage map.
#pragma once
#include <vector>

namespace cloudviewer {

/// Layer-mode coverage map: n x n texels, RG interleaved (coverage, cloud type), tileable fBm.
const std::vector<float>& coverage_map(int n = 256);

}  // namespace cloudviewer
