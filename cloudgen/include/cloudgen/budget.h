// A voxel budget (`cloudgen generate --voxel-budget 200M`): the voxel size whose active voxel count
// fits a budget, chosen before generating from a sampled estimate and the skipping bound.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "cloudgen/preset.h"

namespace cloudgen {

/// A count like 200M, 1.5G, 64K or 5000000 (K = 1e3, M = 1e6, G = 1e9: voxels, not bytes), at
/// least `min`; throws InputError naming `flag`, the text and the allowed form.
uint64_t parse_voxel_count(const std::string& text, const std::string& flag, uint64_t min);

struct BudgetChoice {
  uint64_t budget = 0;
  uint32_t longest = 0;                 ///< voxels along the longest axis (what --resolution N sets)
  std::array<uint32_t, 3> resolution{};  ///< the chosen resolution
  double voxel_size = 0;                 ///< m, the world extent kept
  std::array<uint32_t, 3> sample{};      ///< the resolution the active fraction was measured at
  double fraction = 0;                   ///< active voxels / voxels in the sample
  uint64_t estimate = 0;                 ///< fraction x the chosen resolution's voxels
  uint64_t bound = 0;                    ///< voxels of the bricks the skipping bound keeps (a ceiling)
};

/// The largest resolution (world extent kept, as rescale) whose estimated active voxels fit
/// `budget`. The estimate is the active fraction of the preset generated at about 2 M voxels (the
/// fraction of space that holds cloud does not depend on the voxel size), times the voxel count,
/// and never more than the skipping bound, which counts every voxel of every brick it cannot rule
/// out (1.6-5.3x the active count on the shipped presets, docs/notes/voxel-budget.md). Deterministic.
BudgetChoice choose_for_budget(const Preset& p, uint64_t budget, int threads = 0);

/// One line for the user: the choice, the estimate, the sample and the bound.
std::string describe(const BudgetChoice& c);

}  // namespace cloudgen
