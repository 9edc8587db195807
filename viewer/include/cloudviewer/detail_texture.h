// The render-time detail texture (render.detail, shaders/medium.glsl fine_detail): a small tileable
// Worley fBm that erodes the density near the cloud's boundary at a physical period, finer than
// the voxels (Schneider 2015/2017: Nubis's separate 32^3 detail texture, tiled at a high frequency).
#pragma once
#include <memory>
#include <vector>

namespace cloudviewer {

/// Lattice of the detail's base Worley octave per tile: 3 octaves at 4, 8 and 16 cells per tile.
inline constexpr int kDetailBaseCells = 4;
inline constexpr int kDetailOctaves = 3;
inline constexpr unsigned long long kDetailSeed = 0xde7a11c10d5ull;

/// The detail texture of edge `size` (render.detail_size, 32..128): size^3 values, x fastest, of
/// libnoise3d's inverted Worley fBm (kDetailOctaves octaves, gain 0.5, lacunarity 2, base period
/// kDetailBaseCells cells) sampled over exactly one tile, so the texture repeats seamlessly on
/// every axis; stretched linearly to [0, 1] by its own minimum and maximum. Deterministic (a fixed
/// seed, the same values for any thread count); made at its first use for a size and kept.
std::shared_ptr<const std::vector<float>> detail_texture(int size);

}  // namespace cloudviewer
