// What a volume costs in memory and on the GPU, what the machine has, and the choice between the
// dense texture and NanoVDB that follows.
#pragma once
#include <cstdint>
#include <string>

#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudviewer {

/// Bytes the dense path's budget allows (render.dense_budget MiB, or a third of the free memory when 0).
uint64_t dense_budget_bytes(const RenderSettings& s);
/// The largest RGBA32F texture render.volume=auto sends to the dense path: 2 GiB.
constexpr uint64_t kDenseTextureLimit = uint64_t(1) << 31;
/// Whether INPUT of `voxels` voxels goes through NanoVDB under s.volume (auto: the dense texture
/// and occupancy, prepared_bytes(voxels), exceed dense_budget_bytes(s), or the texture alone
/// kDenseTextureLimit).
bool use_nanovdb(const RenderSettings& s, uint64_t voxels);
/// Bytes the volume occupies on the GPU under `lookup` (render.nanovdb_lookup): the RGBA32F
/// texture, or the NanoVDB buffer and its leaf page table (8 bytes per 8^3 cell, when every grid
/// has one; atlas: neither, the GL renderer reports the atlas it builds), plus the R8 occupancy and R8UI
/// distance textures.
uint64_t volume_gpu_bytes(const PreparedVolume& v, NanoLookup lookup);
/// Bytes of the NanoVDB grids (0 for a dense volume).
uint64_t nano_grid_bytes(const PreparedVolume& v);
/// Bytes of memory this process may still allocate (MemAvailable, or physical memory).
uint64_t available_memory_bytes();
/// Throws InputError naming `what`, the estimate and what is available when `bytes` will not fit.
void check_memory(const std::string& what, uint64_t bytes);

}  // namespace cloudviewer
