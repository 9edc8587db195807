// The render-time detail texture (render.detail, shaders/medium.glsl fine_detail): a small tileable
// Worley fBm that erodes the density near the cloud's boundary at a physical period, finer than
// the voxels (Schneider 2015/2017: Nubis's separate 32^3 detail texture, tiled at a high frequency).
#pragma once
#include <memory>
#include <vector>

#include "cloudgen/detail_noise.h"

namespace cloudviewer {

// Its noise (lattice, octaves, seed) is cloudgen's (cloudgen/detail_noise.h), which the texture
// pack ships too.
using cloudgen::kDetailBaseCells;
using cloudgen::kDetailOctaves;
using cloudgen::kDetailSeed;

/// The detail texture of edge `size` (render.detail_size, 32..128): size^3 values, x fastest, of
/// libnoise3d's inverted Worley fBm (kDetailOctaves octaves, gain 0.5, lacunarity 2, base period
/// kDetailBaseCells cells) sampled over exactly one tile, so the texture repeats seamlessly on
/// every axis; stretched linearly to [0, 1] by its own minimum and maximum. Deterministic (a fixed
/// seed, the same values for any thread count); made at its first use for a size and kept.
std::shared_ptr<const std::vector<float>> detail_texture(int size);

}  // namespace cloudviewer
