// Synthetic volumes for development and tests (no cloudgen needed), and the tileable fBm they and
// the layer-mode coverage map are made of.
#include <algorithm>
#include <cmath>

#include "noise3d/noise3d.h"

#include "cloudviewer/errors.h"
#include "cloudviewer/scene.h"
#include "internal.h"

namespace cloudviewer {

// Tileable fBm in [0, 1] for the synthetic volumes, from libnoise3d's Perlin fBm (std 0.16 on
// [-1, 1]); 0.5 + 0.8 v gives mean 0.5 and std ~0.13.
double tileable_fbm(double x, double y, double z, int period, int octaves, uint32_t seed) {
  noise3d::FractalParams p;
  p.kind = noise3d::Kind::Perlin;
  p.period = noise3d::Period::cube(uint32_t(period));
  p.octaves = octaves;
  p.seed = seed;
  return std::clamp(0.5 + 0.8 * noise3d::evaluate(p, x, y, z), 0.0, 1.0);
}

namespace {

void fill_detail(cloudgen::Volume& v) {
  const auto& d = v.dims;
  for (int c = 0; c < 3; ++c) v.detail[c].assign(v.voxel_count(), 0.f);
  for (uint32_t z = 0; z < d[2]; ++z)
    for (uint32_t y = 0; y < d[1]; ++y)
      for (uint32_t x = 0; x < d[0]; ++x) {
        double u = (x + 0.5) / d[0], w = (z + 0.5) / d[2], h = (y + 0.5) / d[1];
        for (int c = 0; c < 3; ++c) {
          int period = 4 << c;
          v.detail[c][v.index(x, y, z)] = float(tileable_fbm(u * period, h * period, w * period, period, 2, 11 + c));
        }
      }
}

}  // namespace

cloudgen::Volume synthetic_volume(const std::string& kind) {
  cloudgen::Volume v;
  if (kind == "slab") {
    v.dims = {32, 8, 32};
    v.voxel_size = 5;
    v.origin = {-80, 60, -80};
    v.density.assign(v.voxel_count(), 1.f);
  } else if (kind == "sphere") {
    v.dims = {64, 64, 64};
    v.voxel_size = 10;
    v.origin = {-320, 300, -320};
    v.density.assign(v.voxel_count(), 0.f);
    for (uint32_t z = 0; z < 64; ++z)
      for (uint32_t y = 0; y < 64; ++y)
        for (uint32_t x = 0; x < 64; ++x) {
          double px = (x + 0.5) / 64 - 0.5, py = (y + 0.5) / 64 - 0.5, pz = (z + 0.5) / 64 - 0.5;
          double r = std::sqrt(px * px + py * py + pz * pz) / 0.35;
          double n = tileable_fbm((x + 0.5) / 16, (y + 0.5) / 16, (z + 0.5) / 16, 4, 3, 5);
          double d = std::clamp((1.0 - r) * 4.0 + (n - 0.5) * 1.5, 0.0, 1.0);
          v.density[v.index(x, y, z)] = float(d);
        }
    fill_detail(v);
  } else if (kind == "blob" || kind == "noise") {
    v.dims = {96, 48, 96};
    v.voxel_size = 12;
    v.origin = {-576, 300, -576};
    v.tiles_xz = (kind == "noise");
    v.density.assign(v.voxel_count(), 0.f);
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x) {
          double u = (x + 0.5) / v.dims[0], w = (z + 0.5) / v.dims[2], h = (y + 0.5) / v.dims[1];
          double hd = (1 - std::exp(-50 * h)) * std::exp(-4 * h) / 0.70;  // thesis HD(h), peak ~0.7
          double n = tileable_fbm(u * 4, h * 2, w * 4, 4, 4, 7);
          double d = n * hd;
          if (kind == "blob") {  // one cumulus in the middle, zero at the sides
            double rx = (u - 0.5) / 0.4, rz = (w - 0.5) / 0.4;
            d *= std::max(0.0, 1.0 - (rx * rx + rz * rz));
            d *= 2.0;
          }
          double t = 0.38;
          d = std::clamp((d - t) / (1 - t), 0.0, 1.0);
          v.density[v.index(x, y, z)] = float(d);
        }
    fill_detail(v);
  } else {
    throw InputError("unknown synthetic input 'synthetic:" + kind + "' (allowed: sphere, slab, blob, noise)");
  }
  v.metadata.push_back({"source", "synthetic:" + kind});
  return v;
}

}  // namespace cloudviewer
