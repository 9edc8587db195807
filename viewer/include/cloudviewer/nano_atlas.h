// render.nanovdb_lookup=atlas: the occupied leaves of a NanoVDB volume as bricks of one 3D texture.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cloudviewer/prepared_volume.h"

namespace cloudviewer {

/// render.nanovdb_lookup=atlas (GL): the occupied part of the volume as bricks of a 3D texture the
/// texture unit filters, the usual GPU sparse-volume layout. Brick cell c (per axis) holds the
/// dense texels 8 c - 1 .. 8 c + 7 (9 per axis: a trilinear lookup whose lower corner i0 has
/// (i0 + 1) >> 3 == c finds its 8 corners in that brick), clamped or wrapped at the volume's sides
/// as the dense texture's sampler does. A cell whose 9^3 densities are all 0 has no brick (the
/// lookup returns 0). Values are the dense texture's, bit for bit (nanovdb_texel).
struct NanoAtlas {
  static constexpr int kBrick = 9;
  std::array<int, 3> cells{{0, 0, 0}};   ///< brick cells per axis: dims / 8 + 1 (0: no atlas)
  std::array<int, 3> layout{{0, 0, 0}};  ///< bricks per axis of the atlas texture
  int channels = 1;                      ///< 1: density; 4: density and the three detail values
  size_t bricks = 0;
  std::vector<uint16_t> index;  ///< per cell x fastest: the brick's first texel (x, y, z) and 1; all 0: none
  std::vector<float> texels;    ///< channels per texel, x fastest, layout * kBrick texels per axis
  uint64_t bytes() const { return uint64_t(index.size()) * 2 + uint64_t(texels.size()) * 4; }
};
/// The atlas of a nanovdb volume; none (cells 0) when a texture side would exceed max_side texels
/// or the atlas max_bytes. Needs cloudgen.
NanoAtlas build_nano_atlas(const PreparedVolume& v, int max_side, uint64_t max_bytes);

}  // namespace cloudviewer
