// A preset's noise channel as the generator evaluates it: the channel resolved into libnoise3d
// parameters (periods derived from the aspect ratio), and the noise value mapped to what a voxel
// stores. The preset reader validates the resolved parameters; generate.cpp evaluates them.
#pragma once

#include "cloudgen/preset.h"
#include "noise3d/noise3d.h"

namespace cloudgen {

/// The noise parameters of a channel (0 = r .. 3 = a) as used by the generator: a period of 0 on y
/// or z is derived from x and the resolution's aspect ratio, so every channel wraps with the volume.
noise3d::FractalParams channel_params(const Preset& p, int channel);

/// The noise parameters of the coverage map (sampled over x and z, y = 0): its z period follows
/// x's by the aspect ratio, like a channel's.
noise3d::FractalParams coverage_params(const Preset& p);

/// A noise value of kind `k` mapped to [0, 1] (Perlin fBm is in [-1, 1]).
float noise_to_unit(noise3d::Kind k, float v);

/// What a voxel of the channel stores for noise value v: to [0, 1], the contrast remap (identity
/// for [0, 1] leaves bytes unchanged), then invert. Out of line on purpose: inlined into the
/// generator's brick loop it made generation 8% slower (thesis 192^3, one thread, measured).
float channel_value(const Channel& ch, float v);

}  // namespace cloudgen
