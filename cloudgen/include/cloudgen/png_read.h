// One PNG decoder for the images cloudgen reads (flow maps, weather maps): libpng from memory,
// values as stored (palettes expanded to RGB; no gamma or colour-space conversion), its errors
// (reported by longjmp) turned into InputError. The caller checks the header before any row is
// allocated, so a hostile header cannot make it allocate more than its own limit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace cloudgen {

struct PngHeader {
  uint32_t width = 0, height = 0;
  int depth = 0;       ///< bits per sample as stored: 1, 2, 4, 8 or 16
  bool colour = false;  ///< RGB, RGBA or a palette (else grey or grey + alpha)
  bool palette = false;
};

struct PngPixels {
  uint32_t width = 0, height = 0;
  int depth = 0;     ///< 8 or 16 after palette expansion
  int channels = 0;  ///< samples per texel as decoded (grey 1, grey+alpha 2, RGB 3, RGBA 4)
  size_t row_bytes = 0;
  std::vector<uint8_t> bytes;
  /// Sample c of texel (i, j), j = 0 the top row, as an integer of `depth` bits.
  unsigned value(size_t i, size_t j, int c) const {
    const uint8_t* px = bytes.data() + j * row_bytes + (i * size_t(channels) + size_t(c)) * (depth == 16 ? 2 : 1);
    return depth == 16 ? (unsigned(px[0]) << 8) | px[1] : px[0];
  }
};

/// True when `data` starts with the PNG signature.
bool is_png(const uint8_t* data, size_t size);

/// Decodes the PNG in `data`. `check` sees the header first and throws to refuse it. A libpng error
/// becomes InputError(what + ": " + libpng's message + suffix).
PngPixels decode_png(const uint8_t* data, size_t size, const std::string& what,
                     const std::function<void(const PngHeader&)>& check, const std::string& suffix = "");

}  // namespace cloudgen
