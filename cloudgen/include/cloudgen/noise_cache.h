// The raw noise of a preset's channels, kept between generate() runs (GenerateOptions::noise_cache)
// so that an edit re-runs only what it changes: a threshold, coverage, density, remap,
// height-profile or tower edit recombines the cached noise; only a change of a channel's noise
// parameters (seed, kind, period, octaves, gain, lacunarity, ...) or of the resolution evaluates
// it again. The values after the noise are computed as in a cold run, so the bytes are the same.
// The noise-free shape factor (profile, towers, coverage or shape sources) is kept per brick as
// well, for the edits that do not change it (threshold, density, a channel's remap).
#pragma once

#include <cstddef>
#include <memory>

namespace cloudgen {

struct Volume;

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
  /// Takes back a volume a generate() with this cache returned, once its values are no longer
  /// needed: the next generate() fills its channels' memory instead of new memory (a 256^3 volume's
  /// fresh pages cost about as much as recombining it). Only the memory is reused, never a value.
  void recycle(Volume&& v);

  struct Impl;  ///< generate.cpp's; one store per channel's noise parameters, one slot per box
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace cloudgen
