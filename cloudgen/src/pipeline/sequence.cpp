// Baking motion into frames (cloudgen/sequence.h): sampling, frame boxes, the loop rule.
#include "cloudgen/sequence.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "cloudgen/cli_parse.h"

namespace cloudgen {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

int64_t mod(int64_t a, int64_t n) { return ((a % n) + n) % n; }

/// The two voxel indices and weights a trilinear read at index coordinate u uses along one axis
/// (voxel centres at integers), or `inside` false when u lies outside the box [-0.5, n - 0.5]
/// and the axis does not wrap (then the value is 0).
struct Taps {
  int64_t i0 = 0, i1 = 0;
  double w0 = 0, w1 = 0;
  bool inside = false;
};
Taps taps(double u, int64_t n, bool wrap) {
  Taps t;
  if (!wrap && !(u >= -0.5 && u <= double(n) - 0.5)) return t;
  const double fl = std::floor(u);
  const double f = u - fl;
  t.i0 = int64_t(fl);
  t.i1 = t.i0 + 1;
  if (wrap) {
    t.i0 = mod(t.i0, n), t.i1 = mod(t.i1, n);
  } else {
    t.i0 = std::clamp<int64_t>(t.i0, 0, n - 1), t.i1 = std::clamp<int64_t>(t.i1, 0, n - 1);
  }
  t.w0 = 1.0 - f;
  t.w1 = f;
  t.inside = true;
  return t;
}

/// The four (y, z) corners of a trilinear read of `s`: their weights and where their x rows start.
struct CornersYZ {
  double w[4];
  size_t base[4];
};
CornersYZ corners_yz(const Volume& s, const Taps& ty, const Taps& tz) {
  CornersYZ c;
  for (int q = 0; q < 4; ++q) {
    const int64_t y = q & 1 ? ty.i1 : ty.i0, z = q & 2 ? tz.i1 : tz.i0;
    c.w[q] = (q & 1 ? ty.w1 : ty.w0) * (q & 2 ? tz.w1 : tz.w0);
    c.base[q] = s.index(0, uint32_t(y), uint32_t(z));
  }
  return c;
}
/// Channel `ch` of `s` read trilinearly at those corners and the x taps.
double trilinear(const float* ch, const CornersYZ& c, const Taps& tx) {
  double acc = 0;
  for (int q = 0; q < 4; ++q)
    acc += c.w[q] * (tx.w0 * double(ch[c.base[q] + size_t(tx.i0)]) + tx.w1 * double(ch[c.base[q] + size_t(tx.i1)]));
  return acc;
}

}  // namespace

FrameRange parse_frames(const std::string& text, const std::string& flag) {
  const std::string allowed = "expected A:B (frame numbers 0 <= A <= B <= " + std::to_string(kMaxFrameNumber) +
                              ", at most " + std::to_string(kMaxSequenceFrames) + " frames) or one frame A";
  const size_t colon = text.find(':');
  FrameRange r;
  try {
    if (colon == std::string::npos) {
      r.first = r.last = int64_t(parse_uint(text, flag, uint64_t(kMaxFrameNumber)));
    } else {
      r.first = int64_t(parse_uint(text.substr(0, colon), flag, uint64_t(kMaxFrameNumber)));
      r.last = int64_t(parse_uint(text.substr(colon + 1), flag, uint64_t(kMaxFrameNumber)));
    }
  } catch (const InputError&) {
    throw InputError(flag + " " + text + ": " + allowed);
  }
  if (r.last < r.first) throw InputError(flag + " " + text + ": the last frame is before the first; " + allowed);
  if (r.count() > kMaxSequenceFrames)
    throw InputError(flag + " " + text + ": " + std::to_string(r.count()) + " frames; " + allowed);
  return r;
}

double parse_fps(const std::string& text, const std::string& flag) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v) || !(v > 0) ||
      v > 1000)
    throw InputError(flag + " " + text + ": expected frames per second, a number in (0, 1000] (time = frame / fps)");
  return v;
}

namespace {
/// [begin, end) of the last run of '#' in the file-name part of `path`; begin == end when none.
std::pair<size_t, size_t> hash_run(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t name = slash == std::string::npos ? 0 : slash + 1;
  const size_t end = path.find_last_of('#');
  if (end == std::string::npos || end < name) return {0, 0};
  size_t begin = end;
  while (begin > name && path[begin - 1] == '#') --begin;
  return {begin, end + 1};
}
}  // namespace

bool has_frame_pattern(const std::string& path) {
  const auto [b, e] = hash_run(path);
  return e > b;
}

std::string frame_path(const std::string& pattern, int64_t frame) {
  const auto [b, e] = hash_run(pattern);
  if (e == b) return pattern;
  std::string num = std::to_string(frame);
  if (num.size() < e - b) num.insert(0, e - b - num.size(), '0');
  return pattern.substr(0, b) + num + pattern.substr(e);
}

MotionBox motion_box(const Volume& v) {
  MotionBox b;
  b.dims = v.dims;
  b.voxel_size = v.voxel_size;
  b.origin = v.origin;
  b.tiles_xz = v.tiles_xz;
  // A region or tile of a preset measures heights in the whole preset's box (volume_header
  // records it), so its frames move like the one-process volume's.
  double min_y = 0, height = 0;
  if (motion_height_box(v.metadata, min_y, height)) {
    b.origin[1] = min_y;
    b.dims[1] = uint32_t(std::max(1.0, std::round(height / v.voxel_size)));
  }
  return b;
}

glm::dvec3 motion_velocity(const MotionParams& m, double t, double h) {
  return (motion_displacement(m, t + kVelocityStep, h) - motion_displacement(m, t - kVelocityStep, h)) /
         (2.0 * kVelocityStep);
}

MotionParams loop_motion(const MotionParams& m, double T, const MotionBox& box, std::vector<std::string>* notes) {
  MotionParams out = m;
  auto note = [&](const std::string& s) {
    if (notes) notes->push_back(s);
  };
  if (!(T > 0)) throw InputError("--loop: the sequence lasts no time");
  if (m.wind_speed > 0) {
    if (!box.tiles_xz)
      throw InputError("--loop: motion.wind_speed = " + fmt(m.wind_speed) +
                       " m/s carries a box (tiling = false) volume's cloud away, so its sequence cannot loop; set "
                       "--set motion.wind_speed=0 (the flow map still loops) or use a tiling preset");
    if (m.wind_shear > 0)
      throw InputError("--loop: motion.wind_shear = " + fmt(m.wind_shear) +
                       " makes each height travel (1 + shear * h) times as far as the base, so no wind speed brings "
                       "every height back onto a whole tile; set --set motion.wind_shear=0 (or motion.wind_speed=0)");
    const glm::dvec2 dir = motion_glsl::wind_direction_xz(m.wind_direction);
    const double lx = box.dims[0] * box.voxel_size, lz = box.dims[2] * box.voxel_size;
    const double kx = std::round(m.wind_speed * T * dir.x / lx), kz = std::round(m.wind_speed * T * dir.y / lz);
    const double tx = kx * lx, tz = kz * lz;
    out.wind_speed = std::hypot(tx, tz) / T;
    if (out.wind_speed == 0) {
      out.wind_direction = m.wind_direction;
      note("motion.wind_speed " + fmt(m.wind_speed) + " -> 0 m/s: in " + fmt(T) + " s the wind travels less than half a tile (" +
           fmt(lx) + " x " + fmt(lz) + " m); a looping wind needs at least " + fmt(std::min(lx, lz) / T) + " m/s");
    } else {
      out.wind_direction = std::atan2(tx, -tz) * (360.0 / CV_MOTION_TWO_PI);
      const MotionKey* speed_key = nullptr;
      for (const MotionKey& k : motion_keys())
        if (k.key == "wind_speed") speed_key = &k;
      if (speed_key && out.wind_speed > speed_key->hi)
        throw InputError("--loop: a whole number of tiles in " + fmt(T) + " s needs motion.wind_speed = " +
                         fmt(out.wind_speed) + " m/s, above its maximum " + fmt(speed_key->hi) +
                         "; make the sequence longer or the wind slower");
      note("motion.wind_speed " + fmt(m.wind_speed) + " -> " + fmt(out.wind_speed) + " m/s, motion.wind_direction " +
           fmt(m.wind_direction) + " -> " + fmt(out.wind_direction) + " deg: " + fmt(kx) + " tile(s) along x and " +
           fmt(kz) + " along z in " + fmt(T) + " s");
    }
  }
  if (m.flow_speed > 0 && (m.flow_up > 0 || m.flow_forward > 0)) {
    const double n = std::max(1.0, std::round(m.flow_speed * T));
    out.flow_speed = n / T;
    for (const MotionKey& k : motion_keys())
      if (k.key == "flow_speed" && out.flow_speed > k.hi)
        throw InputError("--loop: one flow cycle in " + fmt(T) + " s needs motion.flow_speed = " + fmt(out.flow_speed) +
                         ", above its maximum " + fmt(k.hi) + "; make the sequence longer");
    if (out.flow_speed != m.flow_speed)
      note("motion.flow_speed " + fmt(m.flow_speed) + " -> " + fmt(out.flow_speed) + " cycles/s: " + fmt(n) +
           " whole flow cycle(s) in " + fmt(T) + " s");
  }
  if (m.curl_amplitude > 0 && m.curl_rise > 0) {
    // The curl field repeats vertically every extent / repeats metres: rise a whole number of those.
    const double ey = box.dims[1] * box.voxel_size;
    const glm::dvec3 rep = curl_repeats(m, glm::dvec3(box.dims[0], box.dims[1], box.dims[2]) * box.voxel_size);
    const double tile = ey / rep.y;
    const double n = std::max(1.0, std::round(m.curl_rise * T / tile));
    out.curl_rise = n * tile / T;
    for (const MotionKey& k : motion_keys())
      if (k.key == "curl_rise" && out.curl_rise > k.hi)
        throw InputError("--loop: a whole curl tile (" + fmt(tile) + " m) in " + fmt(T) + " s needs motion.curl_rise = " +
                         fmt(out.curl_rise) + " m/s, above its maximum " + fmt(k.hi) + "; make the sequence longer");
    if (out.curl_rise != m.curl_rise)
      note("motion.curl_rise " + fmt(m.curl_rise) + " -> " + fmt(out.curl_rise) + " m/s: the curl field rises " + fmt(n) +
           " whole tile(s) of " + fmt(tile) + " m in " + fmt(T) + " s");
  }
  return out;
}

uint64_t FrameBox::voxels() const {
  uint64_t n = 1;
  for (int a = 0; a < 3; ++a) n *= uint64_t(std::max<int64_t>(0, hi[a] - lo[a]));
  return n;
}

FrameBox frame_box(const MotionBox& b, const MotionParams& m, double t) {
  FrameBox fb;
  const int64_t n[3] = {b.dims[0], b.dims[1], b.dims[2]};
  if (b.tiles_xz) {  // the layer's box: x and z wrap, what leaves it vertically is gone
    for (int a = 0; a < 3; ++a) fb.hi[a] = n[a];
    return fb;
  }
  const double vs = b.voxel_size;
  // Rows above the box all have h = 1 (clamped): the same displacement, so a bounded scan finds them.
  const glm::dvec3 top = motion_displacement(m, t, 1.0) / vs;
  const int64_t jmax = n[1] - 1 + std::max<int64_t>(0, int64_t(std::ceil(top.y)) + 1);
  fb.lo = {std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max()};
  fb.hi = {std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min()};
  bool any = false;
  for (int64_t j = 0; j <= jmax; ++j) {  // rows below the box have h = 0: D.y = 0, nothing lands inside
    const double h = height_fraction(b, b.origin[1] + (double(j) + 0.5) * vs);
    const glm::dvec3 d = motion_displacement(m, t, h) / vs;
    const double uy = double(j) - d.y;
    if (!(uy >= -0.5 && uy <= double(n[1]) - 0.5)) continue;
    any = true;
    const double dx[3] = {d.x, d.y, d.z};
    for (int a : {0, 2}) {
      fb.lo[a] = std::min(fb.lo[a], int64_t(std::ceil(-0.5 + dx[a])));
      fb.hi[a] = std::max(fb.hi[a], int64_t(std::floor(double(n[a]) - 0.5 + dx[a])) + 1);
    }
    fb.lo[1] = std::min(fb.lo[1], j);
    fb.hi[1] = std::max(fb.hi[1], j + 1);
  }
  if (!any) fb.lo = {0, 0, 0}, fb.hi = {1, 1, 1};  // everything moved out of sight: one empty voxel
  return fb;
}

double sample_static(const Volume& v, const std::vector<float>& ch, const glm::dvec3& q) {
  const int64_t n[3] = {v.dims[0], v.dims[1], v.dims[2]};
  Taps t[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (q[a] - v.origin[a]) / v.voxel_size - 0.5;
    t[a] = taps(u, n[a], v.tiles_xz && a != 1);
    if (!t[a].inside) return 0.0;
  }
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int64_t x = c & 1 ? t[0].i1 : t[0].i0, y = c & 2 ? t[1].i1 : t[1].i0, z = c & 4 ? t[2].i1 : t[2].i0;
    const double w = (c & 1 ? t[0].w1 : t[0].w0) * (c & 2 ? t[1].w1 : t[1].w0) * (c & 4 ? t[2].w1 : t[2].w0);
    acc += w * double(ch[v.index(uint32_t(x), uint32_t(y), uint32_t(z))]);
  }
  return acc;
}

MotionFrame bake_frame(const Volume& s, const MotionParams& m, int64_t frame, double fps, int threads) {
  MotionFrame f;
  f.frame = frame;
  f.fps = fps;
  f.time = double(frame) / fps;
  f.motion = m;
  f.box = motion_box(s);
  const FrameBox fb = frame_box(f.box, m, f.time);
  const double vs = s.voxel_size;
  Volume& v = f.volume;
  v.voxel_size = vs;
  v.tiles_xz = s.tiles_xz;
  v.metadata = s.metadata;
  // The box the heights were measured in travels with the frame (its own box follows the cloud).
  set_motion_height_box(v.metadata, f.box.min_y(), f.box.height());
  v.detail_names = s.detail_names;
  v.occupancy_cell = s.occupancy_cell;
  v.occupancy_padding = s.occupancy_padding;
  for (int a = 0; a < 3; ++a) {
    v.dims[a] = uint32_t(fb.hi[a] - fb.lo[a]);
    v.origin[a] = fb.lo[a] == 0 ? s.origin[a] : s.origin[a] + double(fb.lo[a]) * vs;
  }
  // The channels to displace: density and every detail channel present.
  std::vector<const std::vector<float>*> src{&s.density};
  std::vector<std::vector<float>*> dst{&v.density};
  for (int c = 0; c < 3; ++c)
    if (!s.detail[c].empty()) src.push_back(&s.detail[c]), dst.push_back(&v.detail[c]);
  for (auto* d : dst) d->assign(v.voxel_count(), 0.0f);

  // D depends on the height of the output point only, so every row j (fixed y) of the frame is the
  // static volume translated by one vector: its taps along x and z are computed once per row.
  const int64_t n[3] = {s.dims[0], s.dims[1], s.dims[2]};
  const uint32_t ny = v.dims[1];
  struct Row {
    Taps y;
    std::vector<Taps> x, z;
    glm::dvec3 d;  // the row's displacement in voxels
    double h = 0;  // its height fraction
  };
  std::vector<Row> rows(ny);
  f.row_velocity.resize(ny);
  for (uint32_t j = 0; j < ny; ++j) {
    const int64_t js = fb.lo[1] + j;
    const double h = height_fraction(f.box, s.origin[1] + (double(js) + 0.5) * vs);
    const glm::dvec3 d = motion_displacement(m, f.time, h) / vs;
    f.row_velocity[j] = motion_velocity(m, f.time, h);
    Row& r = rows[j];
    r.d = d;
    r.h = h;
    r.y = taps(double(js) - d.y, n[1], false);
    r.x.resize(v.dims[0]);
    r.z.resize(v.dims[2]);
    for (uint32_t i = 0; i < v.dims[0]; ++i) r.x[i] = taps(double(fb.lo[0] + i) - d.x, n[0], s.tiles_xz);
    for (uint32_t k = 0; k < v.dims[2]; ++k) r.z[k] = taps(double(fb.lo[2] + k) - d.z, n[2], s.tiles_xz);
  }
  // The curl distortion of the detail (motion.curl_*), over the static volume's box.
  const bool curl_on = m.curl_amplitude > 0 && src.size() > 1;
  const glm::dvec3 dims = glm::dvec3(double(n[0]), double(n[1]), double(n[2]));
  const glm::dvec3 extent = dims * vs;
  const glm::dvec3 curl_rep = curl_repeats(m, extent);
  const double curl_sh = curl_shift(m, f.time, extent.y, curl_rep.y);
  auto body = [&](const tbb::blocked_range<uint32_t>& zr) {
    for (uint32_t k = zr.begin(); k < zr.end(); ++k)
      for (uint32_t j = 0; j < ny; ++j) {
        const Row& r = rows[j];
        const Taps& tz = r.z[k];
        if (!r.y.inside || !tz.inside) continue;
        const CornersYZ row = corners_yz(s, r.y, tz);  // the same for every x of this row and slice
        for (uint32_t i = 0; i < v.dims[0]; ++i) {
          const Taps& tx = r.x[i];
          if (!tx.inside) continue;
          const size_t out = v.index(i, j, k);
          if (curl_on) {
            // The detail channels are read where the curl field moves them (medium.glsl: at the
            // static uvw plus the offset, the texture's clamp or wrap at the box's faces).
            const glm::dvec3 st(double(fb.lo[0] + i) - r.d.x, double(fb.lo[1] + j) - r.d.y, double(fb.lo[2] + k) - r.d.z);
            const glm::dvec3 uvw = (st + 0.5) / dims;
            const glm::dvec3 q = st + curl_detail_offset_m(m, uvw, r.h, curl_rep, curl_sh) / vs;
            auto axis = [&](double u, int a, bool wrap) {
              return taps(wrap ? u : std::clamp(u, -0.5, double(n[a]) - 0.5), n[a], wrap);
            };
            const Taps qx = axis(q.x, 0, s.tiles_xz), qy = axis(q.y, 1, false), qz = axis(q.z, 2, s.tiles_xz);
            const CornersYZ moved = corners_yz(s, qy, qz);
            for (size_t c = 1; c < src.size(); ++c) (*dst[c])[out] = float(trilinear(src[c]->data(), moved, qx));
          }
          for (size_t c = 0; c < (curl_on ? 1 : src.size()); ++c) (*dst[c])[out] = float(trilinear(src[c]->data(), row, tx));
        }
      }
  };
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(tbb::blocked_range<uint32_t>(0, v.dims[2], 1), body); });
  return f;
}

uint64_t frame_memory_estimate(const MotionBox& box, const MotionParams& m, const FrameRange& r, double fps,
                               int channels) {
  uint64_t most = 0;
  // Box volumes change size with time; tileable ones never do (one frame tells).
  const int64_t step = box.tiles_xz ? std::max<int64_t>(1, r.count()) : 1;
  for (int64_t fr = r.first; fr <= r.last; fr += step)
    most = std::max(most, frame_box(box, m, double(fr) / fps).voxels());
  // Dense channels, the OpenVDB trees made from them (about as large again) and the velocity grid.
  return most * 4 * (2 * uint64_t(channels) + 3);
}

}  // namespace cloudgen
