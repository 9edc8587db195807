// The render-time detail texture's noise (render.detail, shaders/medium.glsl fine_detail), defined
// once for the viewer, which makes the texture, and the texture pack, which ships it.
#pragma once

#include <cstdint>
#include <vector>

namespace cloudgen {

/// Lattice of the detail's base Worley octave per tile: 3 octaves at 4, 8 and 16 cells per tile.
inline constexpr uint32_t kDetailBaseCells = 4;
inline constexpr uint32_t kDetailOctaves = 3;
inline constexpr uint64_t kDetailSeed = 0xde7a11c10d5ull;

/// libnoise3d's inverted Worley fBm (gain 0.5, lacunarity 2, base period `cells` per tile) sampled
/// over exactly one tile of edge^3 values, x fastest, so it repeats seamlessly on every axis;
/// stretched linearly to [0, 1] by its own minimum and maximum. Deterministic.
std::vector<float> stretched_worley_fbm(uint32_t edge, uint32_t cells, uint32_t octaves, uint64_t seed);

}  // namespace cloudgen
