// The raw noise of a preset's channels, kept between generate() runs (GenerateOptions::noise_cache)
// so that an edit re-runs only what it changes: a threshold, coverage, density, remap,
// height-profile or tower edit recombines the cached noise; only a change of a channel's noise
// parameters (seed, kind, period, octaves, gain, lacunarity, ...) or of the resolution evaluates
// it again. The values after the noise are computed as in a cold run, so the bytes are the same.
#pragma once

#include <cstddef>
#include <memory>

namespace cloudgen {

class NoiseCache {
 public:
  NoiseCache();
  ~NoiseCache();
  NoiseCache(const NoiseCache&) = delete;
  NoiseCache& operator=(const NoiseCache&) = delete;

  /// Bytes of noise held.
  size_t bytes() const;
  /// Drops everything.
  void clear();

  struct Impl;  ///< generate.cpp's; one store per channel's noise parameters, one slot per box
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace cloudgen
