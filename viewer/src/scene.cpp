#include "cloudviewer/scene.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <mutex>

#include <glm/gtc/matrix_transform.hpp>

#include "noise3d/noise3d.h"

#include "cloudgen/view.h"

#include "cloudviewer/errors.h"

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#if __has_include("cloudgen/generate.h")
#include "cloudgen/generate.h"
#define CLOUDVIEWER_HAS_GENERATE 1
#endif
#endif

namespace cloudviewer {

bool has_cloudgen() {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  return true;
#else
  return false;
#endif
}

namespace {

// Tileable fBm in [0, 1] for the synthetic volumes, from libnoise3d's Perlin fBm (std 0.16 on
// [-1, 1]); 0.5 + 0.8 v gives mean 0.5 and std ~0.13.
double fbm(double x, double y, double z, int period, int octaves, uint32_t seed) {
  noise3d::FractalParams p;
  p.kind = noise3d::Kind::Perlin;
  p.period = noise3d::Period::cube(uint32_t(period));
  p.octaves = octaves;
  p.seed = seed;
  return std::clamp(0.5 + 0.8 * noise3d::evaluate(p, x, y, z), 0.0, 1.0);
}

void fill_detail(cloudgen::Volume& v) {
  const auto& d = v.dims;
  for (int c = 0; c < 3; ++c) v.detail[c].assign(v.voxel_count(), 0.f);
  for (uint32_t z = 0; z < d[2]; ++z)
    for (uint32_t y = 0; y < d[1]; ++y)
      for (uint32_t x = 0; x < d[0]; ++x) {
        double u = (x + 0.5) / d[0], w = (z + 0.5) / d[2], h = (y + 0.5) / d[1];
        for (int c = 0; c < 3; ++c) {
          int period = 4 << c;
          v.detail[c][v.index(x, y, z)] = float(fbm(u * period, h * period, w * period, period, 2, 11 + c));
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
          double n = fbm((x + 0.5) / 16, (y + 0.5) / 16, (z + 0.5) / 16, 4, 3, 5);
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
          double n = fbm(u * 4, h * 2, w * 4, 4, 4, 7);
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

cloudgen::Volume load_volume(const std::string& input) {
  if (input.rfind("synthetic:", 0) == 0) return synthetic_volume(input.substr(10));
  std::error_code ec;
  if (!std::filesystem::exists(input, ec))
    throw InputError("input '" + input + "': no such file");
  if (std::filesystem::is_directory(input, ec))
    throw InputError("input '" + input + "': is a directory, expected a .vdb, .raw/.json, .ktx2 or preset .json file");
  std::string ext = std::filesystem::path(input).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  try {
#ifdef CLOUDVIEWER_HAS_GENERATE
    if (ext == ".json") {
      // A raw texture's sidecar is also .json: cloudgen's reader tells them apart; try it first.
      try {
        return cloudgen::read_volume(input);
      } catch (const cloudgen::Error&) {
        return cloudgen::generate_from_file(input);
      }
    }
#endif
    return cloudgen::read_volume(input);
  } catch (const cloudgen::Error& e) {
    throw InputError(std::string(e.what()));
  }
#else
  throw InputError("input '" + input + "' (" + (ext.empty() ? "no extension" : ext) +
                   "): this cloudviewer was built without the cloudgen library, so it can only open "
                   "synthetic:sphere|slab|blob|noise");
#endif
}

PreparedVolume prepare_volume(const cloudgen::Volume& v, int occ_cell, int occ_padding) {
  PreparedVolume p;
  size_t n = v.voxel_count();
  if (n == 0 || v.density.empty())
    throw InputError("volume has no density channel (not a cloud volume)");
  if (v.density.size() != n)
    throw InputError("volume density has " + std::to_string(v.density.size()) + " values, dims say " +
                     std::to_string(n));
  if (!(v.voxel_size > 0) || !std::isfinite(v.voxel_size))
    throw InputError("volume voxel size must be a positive finite number of metres");
  for (int i = 0; i < 3; ++i) {
    p.dims[i] = int(v.dims[i]);
    if (v.dims[i] > 4096) throw InputError("volume dimension " + std::to_string(v.dims[i]) + " exceeds 4096");
  }
  p.voxel_size = v.voxel_size;
  p.origin = glm::dvec3(v.origin[0], v.origin[1], v.origin[2]);
  p.tiles = v.tiles_xz;
  p.has_detail = true;
  for (int c = 0; c < 3; ++c) {
    if (!v.detail[c].empty() && v.detail[c].size() != n)
      throw InputError("volume detail channel " + std::to_string(c) + " has the wrong size");
    if (v.detail[c].empty()) p.has_detail = false;
  }
  p.rgba.assign(n * 4, 0.f);
  for (size_t i = 0; i < n; ++i) {
    float d = v.density[i];
    if (!std::isfinite(d)) throw InputError("volume density has a non-finite value at voxel " + std::to_string(i));
    p.rgba[i * 4] = std::max(d, 0.f);
    for (int c = 0; c < 3; ++c) p.rgba[i * 4 + 1 + c] = v.detail[c].empty() ? 0.f : v.detail[c][i];
  }
  build_occupancy(p, occ_cell, occ_padding);
  return p;
}

void build_occupancy(PreparedVolume& p, int occ_cell, int occ_padding) {
  // Mark coarse cells holding non-zero voxels, then dilate by `padding` cells (Chebyshev,
  // separable max filter; wraps in x/z for tiling volumes).
  p.occ_cell = occ_cell;
  p.occ_padding = occ_padding;
  for (int i = 0; i < 3; ++i) p.occ_dims[i] = (p.dims[i] + occ_cell - 1) / occ_cell;
  const int cx = p.occ_dims[0], cy = p.occ_dims[1], cz = p.occ_dims[2];
  std::vector<uint8_t> occ(size_t(cx) * cy * cz, 0);
  for (int z = 0; z < p.dims[2]; ++z)
    for (int y = 0; y < p.dims[1]; ++y)
      for (int x = 0; x < p.dims[0]; ++x)
        if (p.rgba[((size_t(z) * p.dims[1] + y) * p.dims[0] + x) * 4] > 0.f)
          occ[(size_t(z / occ_cell) * cy + y / occ_cell) * cx + x / occ_cell] = 1;
  auto idx = [&](int x, int y, int z) { return (size_t(z) * cy + y) * cx + x; };
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<uint8_t> out(occ.size(), 0);
    int len = p.occ_dims[axis];
    bool wrap = p.tiles && axis != 1;
    for (int z = 0; z < cz; ++z)
      for (int y = 0; y < cy; ++y)
        for (int x = 0; x < cx; ++x) {
          if (!occ[idx(x, y, z)]) continue;
          int c[3] = {x, y, z};
          for (int d = -occ_padding; d <= occ_padding; ++d) {
            int q[3] = {x, y, z};
            q[axis] = c[axis] + d;
            if (wrap) q[axis] = ((q[axis] % len) + len) % len;
            else if (q[axis] < 0 || q[axis] >= len) continue;
            out[idx(q[0], q[1], q[2])] = 1;
          }
        }
    occ.swap(out);
  }
  size_t count = 0;
  for (uint8_t o : occ) count += o;
  p.occupied_fraction = occ.empty() ? 0 : double(count) / double(occ.size());
  p.occ = std::move(occ);
}

glm::dvec3 Sun::direction() const {
  double az = glm::radians(azimuth_deg), el = glm::radians(elevation_deg);
  return glm::dvec3(std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az));
}

Camera default_camera(const PreparedVolume& vol, double fov_y_deg, double aspect) {
  glm::dvec3 s = vol.size(), c = vol.center();
  double tv = std::tan(glm::radians(fov_y_deg) * 0.5);
  double th = tv * aspect;
  double dist = std::max(0.5 * s.x / th, 0.5 * s.y / tv) * 1.15 + 0.5 * s.z;
  Camera cam;
  cam.fov_y_deg = fov_y_deg;
  cam.target = c;
  cam.eye = c + glm::dvec3(0.0, 0.08 * s.y, -dist);
  return cam;
}

Sun default_sun(const Camera& cam) {
  glm::dvec3 v = cam.eye - cam.target;
  Sun sun;
  sun.azimuth_deg = (v.x == 0 && v.z == 0) ? 0.0 : glm::degrees(std::atan2(v.x, -v.z));
  sun.elevation_deg = 35;
  return sun;
}

namespace {
std::mutex g_mie_mutex;
std::vector<float> g_mie_override;
}  // namespace

void load_mie_table(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mie_mutex);
  if (path.empty()) {
    g_mie_override.clear();
    return;
  }
  std::ifstream in(path);
  if (!in) throw InputError("--mie-table " + path + ": no such file");
  std::vector<double> theta, value;
  std::string line;
  int columns = 0, line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::vector<double> nums;
    double d;
    while (ls >> d) nums.push_back(d);
    if (!ls.eof()) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": not a number");
    if (nums.empty()) continue;
    if (columns == 0) columns = int(nums.size());
    if (int(nums.size()) != columns || columns > 2)
      throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": expected " +
                       (columns == 2 ? "2 columns (theta_degrees value)" : "1 value per line"));
    for (double x : nums)
      if (!std::isfinite(x)) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": not finite");
    if (columns == 2) theta.push_back(nums[0]), value.push_back(nums[1]);
    else value.push_back(nums[0]);
    if (value.back() < 0) throw InputError("--mie-table " + path + ":" + std::to_string(line_no) + ": negative phase value");
  }
  if (value.size() < 2) throw InputError("--mie-table " + path + ": needs at least 2 values");
  if (columns == 1)
    for (size_t i = 0; i < value.size(); ++i) theta.push_back(180.0 * double(i) / double(value.size() - 1));
  for (size_t i = 1; i < theta.size(); ++i)
    if (!(theta[i] > theta[i - 1])) throw InputError("--mie-table " + path + ": theta must increase");
  if (theta.front() > 1e-6 || theta.back() < 180 - 1e-6)
    throw InputError("--mie-table " + path + ": theta must cover 0 to 180 degrees");
  const int n = 1801;
  std::vector<double> t(n);
  size_t j = 0;
  for (int i = 0; i < n; ++i) {
    double th = 180.0 * i / (n - 1);
    while (j + 2 < theta.size() && theta[j + 1] < th) ++j;
    double f = std::clamp((th - theta[j]) / (theta[j + 1] - theta[j]), 0.0, 1.0);
    t[size_t(i)] = value[j] + f * (value[j + 1] - value[j]);
  }
  double integral = 0;
  for (int i = 0; i + 1 < n; ++i) {
    double t0 = M_PI * i / (n - 1), t1 = M_PI * (i + 1) / (n - 1);
    integral += 0.5 * (t[size_t(i)] * std::sin(t0) + t[size_t(i + 1)] * std::sin(t1)) * (t1 - t0);
  }
  integral *= 2 * M_PI;
  if (!(integral > 0)) throw InputError("--mie-table " + path + ": the phase function integrates to 0");
  g_mie_override.resize(n);
  for (int i = 0; i < n; ++i) g_mie_override[size_t(i)] = float(t[size_t(i)] / integral);
}

const std::vector<float>& mie_phase_table(int n) {
  static std::vector<float> table;
  static int cached_n = 0;
  std::lock_guard<std::mutex> lock(g_mie_mutex);
  if (!g_mie_override.empty()) return g_mie_override;
  if (cached_n == n) return table;
  // Lorenz-Mie series (Bohren & Huffman's BHMIE) for water droplets, averaged over Deirmendjian's
  // C.1 cloud size distribution n(r) ~ r^6 exp(-1.5 r), r in micrometres (mode 4 um), weighted by
  // each droplet's scattering (|S1|^2 + |S2|^2 sums already carry the cross-section).
  using cd = std::complex<double>;
  const double lambda_um = 0.55;
  const cd m(1.333, 0.0);
  std::vector<double> mu(size_t(n), 0.0), acc(size_t(n), 0.0);
  for (int j = 0; j < n; ++j) mu[size_t(j)] = std::cos(M_PI * j / (n - 1));
  const int radii = 48;
  const double r_min = 0.5, r_max = 16.0;
  for (int ri = 0; ri < radii; ++ri) {
    double r = r_min + (r_max - r_min) * (ri + 0.5) / radii;
    double weight = std::pow(r, 6) * std::exp(-1.5 * r);
    double x = 2 * M_PI * r / lambda_um;
    cd y = m * x;
    int nstop = int(x + 4 * std::cbrt(x) + 2);
    int nmx = int(std::max(double(nstop), std::abs(y))) + 16;
    std::vector<cd> D(size_t(nmx) + 1, cd(0, 0));
    for (int k = nmx; k >= 2; --k) D[size_t(k - 1)] = double(k) / y - 1.0 / (D[size_t(k)] + double(k) / y);
    double psi0 = std::cos(x), psi1 = std::sin(x), chi0 = -std::sin(x), chi1 = std::cos(x);
    cd xi1(psi1, -chi1);
    std::vector<double> pi0(size_t(n), 0.0), pi1(size_t(n), 1.0);
    std::vector<cd> s1(size_t(n), 0.0), s2(size_t(n), 0.0);
    for (int k = 1; k <= nstop; ++k) {
      double fn = (2.0 * k + 1) / (double(k) * (k + 1));
      double psi = (2.0 * k - 1) * psi1 / x - psi0;
      double chi = (2.0 * k - 1) * chi1 / x - chi0;
      cd xi(psi, -chi);
      cd da = D[size_t(k)] / m + double(k) / x;
      cd db = D[size_t(k)] * m + double(k) / x;
      cd an = (da * psi - psi1) / (da * xi - xi1);
      cd bn = (db * psi - psi1) / (db * xi - xi1);
      for (int j = 0; j < n; ++j) {
        double p = pi1[size_t(j)];
        double t = k * mu[size_t(j)] * p - (k + 1) * pi0[size_t(j)];
        s1[size_t(j)] += fn * (an * p + bn * t);
        s2[size_t(j)] += fn * (an * t + bn * p);
        double pn = ((2.0 * k + 1) * mu[size_t(j)] * p - (k + 1) * pi0[size_t(j)]) / k;
        pi0[size_t(j)] = p;
        pi1[size_t(j)] = pn;
      }
      psi0 = psi1, psi1 = psi, chi0 = chi1, chi1 = chi;
      xi1 = cd(psi1, -chi1);
    }
    for (int j = 0; j < n; ++j) acc[size_t(j)] += weight * 0.5 * (std::norm(s1[size_t(j)]) + std::norm(s2[size_t(j)]));
  }
  // Normalise: 2 pi * integral p(theta) sin(theta) dtheta = 1 (trapezoid on the table's own grid,
  // the same piecewise-linear function the renderers interpolate).
  double integral = 0;
  for (int j = 0; j + 1 < n; ++j) {
    double t0 = M_PI * j / (n - 1), t1 = M_PI * (j + 1) / (n - 1);
    integral += 0.5 * (acc[size_t(j)] * std::sin(t0) + acc[size_t(j + 1)] * std::sin(t1)) * (t1 - t0);
  }
  integral *= 2 * M_PI;
  table.resize(size_t(n));
  for (int j = 0; j < n; ++j) table[size_t(j)] = float(acc[size_t(j)] / integral);
  cached_n = n;
  return table;
}

const std::vector<float>& coverage_map(int n) {
  static std::mutex mutex;
  static std::vector<float> map;
  static int cached = 0;
  std::lock_guard<std::mutex> lock(mutex);
  if (cached == n) return map;
  map.assign(size_t(n) * n * 2, 0.f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double u = (x + 0.5) / n, v = (y + 0.5) / n;
      double c = fbm(u * 4, v * 4, 0.5, 4, 4, 21);
      double t = fbm(u * 2, v * 2, 7.5, 2, 2, 33);
      map[(size_t(y) * n + x) * 2] = float(std::clamp((c - 0.38) / 0.3, 0.0, 1.0));
      map[(size_t(y) * n + x) * 2 + 1] = float(std::clamp((t - 0.3) / 0.4, 0.0, 1.0));
    }
  cached = n;
  return map;
}

double ground_height(const PreparedVolume& vol, const RenderSettings& s) {
  if (!s.ground_height_auto) return s.ground_height;
  return s.mode == PlaceMode::Layer ? 0.0 : std::min(0.0, vol.origin.y);
}

glm::dvec2 layer_altitudes(const PreparedVolume& vol, const RenderSettings& s) {
  double top = s.layer_top > 0 ? s.layer_top : s.layer_bottom + vol.size().y;
  if (top <= s.layer_bottom)
    throw InputError("render.layer_top (" + std::to_string(top) + " m) must be above render.layer_bottom (" +
                     std::to_string(s.layer_bottom) + " m)");
  return glm::dvec2(s.layer_bottom, top);
}

glm::dvec3 volume_space_to_world(const PreparedVolume& vol, const RenderSettings& s, const glm::dvec3& uvw) {
  if (s.mode != PlaceMode::Layer) return vol.origin + uvw * vol.size();
  glm::dvec2 alt = layer_altitudes(vol, s);
  glm::dvec3 size = vol.size();
  return glm::dvec3(uvw.x * size.x, ground_height(vol, s) + alt.x + uvw.y * (alt.y - alt.x), uvw.z * size.z);
}

Camera default_camera(const PreparedVolume& vol, const RenderSettings& s, double fov_y_deg, double aspect) {
  if (s.mode != PlaceMode::Layer) return default_camera(vol, fov_y_deg, aspect);
  glm::dvec2 alt = layer_altitudes(vol, s);
  Camera cam;
  cam.fov_y_deg = fov_y_deg;
  cam.eye = glm::dvec3(0.0, ground_height(vol, s) + 0.4 * alt.x, 0.0);
  cam.target = cam.eye + glm::dvec3(0.0, 0.22, 1.0) * 1000.0;
  return cam;
}

glm::dmat4 view_projection(const Camera& cam, int width, int height) {
  glm::dvec3 dir = cam.target - cam.eye;
  if (glm::length(dir) < 1e-9) dir = glm::dvec3(0, 0, 1);
  dir = glm::normalize(dir);
  glm::dvec3 up = std::abs(dir.y) > 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  glm::dmat4 view = glm::lookAt(glm::dvec3(0.0), dir, up);
  glm::dmat4 proj = glm::perspective(glm::radians(cam.fov_y_deg), double(width) / height, 0.5, 1e6);
  return proj * view;
}

FrameSetup make_frame(const PreparedVolume& vol, const RenderSettings& s, const Camera& cam,
                      const Sun& sun, int width, int height) {
  FrameSetup f;
  f.width = width;
  f.height = height;
  f.camera = cam;
  f.sun = sun;
  f.settings = s;
  const bool layer = s.mode == PlaceMode::Layer;
  if (layer && !vol.tiles)
    throw InputError("render.mode=layer repeats the texture over the sky, so it needs a tileable volume "
                     "(x and z wrap; cloudgen presets and synthetic:noise tile, this input does not)");
  glm::dvec3 size = vol.size();
  glm::dvec2 alt = layer ? layer_altitudes(vol, s) : glm::dvec2(0.0);
  if (layer) size.y = alt.y - alt.x;  // the texture's height stretches over the layer
  glm::dvec3 voxel = size / glm::dvec3(vol.dims[0], vol.dims[1], vol.dims[2]);
  double min_voxel = std::min(voxel.x, std::min(voxel.y, voxel.z));
  double max_extent = std::max(size.x, std::max(size.y, size.z));
  double dt = max_extent / s.steps;
  double cell_m = vol.occ_cell * min_voxel;
  // Large step: k small steps, just under one coarse cell less half a voxel. Why that is safe with
  // any padding >= 1: non-zero density (trilinear reaches half a voxel past a non-empty cell) lies
  // within half a voxel of a non-empty cell, and every unoccupied cell is at least one full cell
  // away from a non-empty one, so a segment shorter than (cell - voxel/2) that starts and ends in
  // unoccupied cells cannot touch density. The march checks both ends of every large step.
  // In layer mode cells are measured in the smallest world voxel edge (the texture may be stretched
  // vertically); the Earth's curvature bends a large step by d^2/2R, far below half a voxel.
  int k = std::max(1, int(std::floor(0.999 * (cell_m - 0.5 * min_voxel) / dt)));
  double diag = glm::length(size);
  ref::CloudParams& p = f.params;
  glm::dvec3 rel_min = vol.origin - cam.eye;
  p.volume_min = glm::dvec4(rel_min, vol.voxel_size);
  p.volume_size = glm::dvec4(size, vol.tiles ? 1.0 : 0.0);  // box mode only, except w
  p.volume_dims = glm::dvec4(vol.dims[0], vol.dims[1], vol.dims[2], vol.has_detail ? 1.0 : 0.0);
  p.occ_dims = glm::dvec4(vol.occ_dims[0], vol.occ_dims[1], vol.occ_dims[2], vol.occ_cell);
  p.sun_dir = glm::dvec4(sun.direction(), s.sun_intensity);
  p.sun_color = glm::dvec4(1.0, 0.96, 0.9, s.ambient);
  p.ambient_color = glm::dvec4(0.30, 0.38, 0.52, s.albedo);
  // Auto values follow the voxel size, not the box, so a VDB cropped to its active voxels renders
  // like the dense texture it came from.
  double sigma = s.sigma_t > 0 ? s.sigma_t : cloudgen::default_extinction_per_metre(min_voxel);
  p.medium = glm::dvec4(sigma, s.erosion, s.density, s.powder_c);
  // Layer rays can run to the horizon: cap the loop (use render.adaptive=true there).
  double max_iter = layer ? 2048.0 + 8.0 * s.steps : 4.0 * std::ceil(diag / dt) + 64.0;
  p.march = glm::dvec4(dt, k, s.max_distance, max_iter);
  double a_start = s.adaptive_start > 0 ? s.adaptive_start : 0.25 * max_extent;
  double a_growth = s.adaptive_growth > 0 ? s.adaptive_growth : 4.0 / max_extent;
  p.march2 = glm::dvec4(s.adaptive ? 1 : 0, a_start, a_growth, s.occupancy ? 1 : 0);
  double light_step = s.light_step > 0 ? s.light_step : 2.5 * min_voxel;
  double light_mode = !s.light_march ? 0.0 : (s.occupancy && s.occupancy_light ? 2.0 : 1.0);
  p.light = glm::dvec4(light_mode, s.light_samples, light_step, s.light_growth);
  p.phase = glm::dvec4(double(int(s.phase)), s.g, double(mie_phase_table().size()), s.powder);
  p.control = glm::dvec4(s.jitter ? 1 : 0, s.frame, s.exact_filter ? 1 : 0, double(int(s.output)));
  double gh = ground_height(vol, s);
  f.ground_half_extent = layer ? 2e5 : 5e4;
  p.ground = glm::dvec4(gh - cam.eye.y, s.ground_albedo, s.ground ? 1 : 0, f.ground_half_extent);
  glm::dvec3 cw = glm::mod(cam.eye, glm::dvec3(1024.0));
  p.camera_world = glm::dvec4(cw, s.shadow_samples);
  p.sky = glm::dvec4(0.12, 0.24, 0.55, 40.0);
  if (layer) {
    double period = size.x * s.coverage_tiles;
    p.layer = glm::dvec4(1.0, alt.x, alt.y, s.earth_radius);
    p.layer2 = glm::dvec4(cam.eye.y - gh, glm::mod(cam.eye.x, size.x), glm::mod(cam.eye.z, size.z), 0.0);
    p.layer3 = glm::dvec4(size.x, 0.0, size.z, period);
    p.layer4 = glm::dvec4(glm::mod(cam.eye.x, period), glm::mod(cam.eye.z, period), s.coverage, s.cloud_type);
    p.volume_size.w = 1.0;
  } else {
    p.layer = p.layer2 = p.layer3 = p.layer4 = glm::dvec4(0.0);
    p.layer.w = s.earth_radius;
  }
  f.params = rounded_to_float(p);
  f.view_proj = view_projection(cam, width, height);
  f.inv_view_proj = glm::dmat4(glm::mat4(glm::inverse(f.view_proj)));
  return f;
}

}  // namespace cloudviewer
