// Temporal upsampling and motion (issue 11, seed 003), measured on the GL renderer:
//  1. frame time of render.temporal=true against full-resolution rendering at 8/16/32/64 steps
//     (GPU timer, best of --repeat, same volume, camera and run), the seed's table;
//  2. error along a moving track (a camera pan with wind), every frame rendered both ways in
//     sequence (so the temporal history is real): RMSE of the display image and the ghosting
//     pixels (any channel off by more than 0.1) per frame, and the frame speed-up there (the
//     camera and the clouds move: the full resolve every frame, where table 1 holds them still);
//  3. the cost of the motion at time 60 s: the flow map against the wind alone (the seed's
//     measure), and wind + flow map against still clouds.
// Usage: bench_temporal VOLUME [--size WxH] [--repeat N] [--frames N] [--csv FILE] [--shader-dir DIR] [--set KEY=VALUE]...
// Prints Markdown tables (scripts/bench_temporal.sh puts them into docs/motion.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "cloudviewer/image.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"

using namespace cloudviewer;

namespace {

Camera orbit(const PreparedVolume& vol, double yaw_deg, double aspect) {
  Camera c = default_camera(vol, 60, aspect);
  glm::dvec3 d = c.eye - c.target;
  double a = glm::radians(yaw_deg);
  c.eye = c.target + glm::dvec3(d.x * std::cos(a) - d.z * std::sin(a), d.y, d.x * std::sin(a) + d.z * std::cos(a));
  return c;
}

int ghosts(const Image& a, const Image& b, double bound) {
  int n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      double d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, double(std::abs(a.at(x, y)[c] - b.at(x, y)[c])));
      n += d > bound;
    }
  return n;
}

// Best GPU time over `repeat` renders of a sequence of `n` frames (frame index advancing, camera
// still), after one warm-up sequence; the temporal history is then in its steady state.
GpuTimings best_of(GlRenderer& r, const PreparedVolume& vol, RenderSettings s, const Camera& cam, const Sun& sun,
                   int w, int h, int repeat) {
  GpuTimings best;
  best.total_ms = 1e300;
  for (int k = 0; k < repeat + 1; ++k) {
    s.frame = k;
    GpuTimings t;
    r.render(make_frame(vol, s, cam, sun, w, h), &t);
    if (k > 0 && t.total_ms < best.total_ms) best = t;
  }
  return best;
}
double best_ms(GlRenderer& r, const PreparedVolume& vol, const RenderSettings& s, const Camera& cam, const Sun& sun,
               int w, int h, int repeat) {
  return best_of(r, vol, s, cam, sun, w, h, repeat).total_ms;
}

const char* kUsage =
    "usage: bench_temporal VOLUME [--size WxH] [--repeat N] [--frames N] [--csv FILE] [--shader-dir DIR] [--set KEY=VALUE]...\n";

struct Args {
  std::string input, csv_path, shader_dir;
  int w = 320, h = 180, repeat = 3, track_frames = 48;
  std::vector<std::string> sets;
};

// False (with the message on stderr) for an unknown option.
bool parse_args(int argc, char** argv, Args& a) {
  a.input = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    std::string k = argv[i], v = argv[i + 1];
    if (k == "--size") std::sscanf(v.c_str(), "%dx%d", &a.w, &a.h);
    else if (k == "--set") a.sets.push_back(v);
    else if (k == "--repeat") a.repeat = std::max(1, std::atoi(v.c_str()));
    else if (k == "--frames") a.track_frames = std::max(2, std::atoi(v.c_str()));
    else if (k == "--csv") a.csv_path = v;
    else if (k == "--shader-dir") a.shader_dir = v;
    else {
      std::cerr << "bench_temporal: unknown option " << k << "\n";
      return false;
    }
  }
  return true;
}

// What every table renders: the volume, the default view, the size and the repeat count.
struct Scene {
  const Args& a;
  RenderSettings base;  // the --set values; every configuration starts from these
  PreparedVolume vol;
  Camera cam;
  Sun sun;
  GpuTimings best_of(GlRenderer& r, const RenderSettings& s) const { return ::best_of(r, vol, s, cam, sun, a.w, a.h, a.repeat); }
};

void print_passes(const std::vector<std::pair<std::string, double>> (&sums)[2], double divisor) {
  for (int k = 0; k < 2; ++k) {
    std::cout << (k ? "\n  temporal:" : "\n  full:");
    for (const auto& [name, ms] : sums[k])
      if (ms / divisor > 0.005) std::printf(" %s %.2f", name.c_str(), ms / divisor);
  }
  std::cout << "\n";
}

// 1. The camera and the clouds still: full against temporal frames per step count, what keeping
// the ground in held frames gains, and every pass at 64 steps.
void still_table(GlRenderer& r, const Scene& sc) {
  std::cout << "The camera and the clouds still (the temporal frames hold their history: clouds_sparse_held):\n\n";
  std::cout << "| steps | full frame ms | temporal frame ms | frame speed-up | full clouds ms | temporal clouds ms | "
               "clouds speed-up |\n|---:|---:|---:|---:|---:|---:|---:|\n";
  std::vector<GpuTimings> per_pass(2);
  for (int steps : {8, 16, 32, 64, 128}) {
    RenderSettings s = sc.base;
    s.steps = steps;
    RenderSettings t = s;
    t.temporal = true;
    GpuTimings full = sc.best_of(r, s);
    GpuTimings temporal = sc.best_of(r, t);
    std::printf("| %d | %.2f | %.2f | %.2fx | %.2f | %.2f | %.2fx |\n", steps, full.total_ms, temporal.total_ms,
                full.total_ms / temporal.total_ms, full.cloud_ms, temporal.cloud_ms, full.cloud_ms / temporal.cloud_ms);
    if (steps == 64) per_pass = {full, temporal};
  }
  {  // what keeping the ground in held frames gains, in this run
    RenderSettings t = sc.base;
    t.steps = 64, t.temporal = true;
    r.set_ground_reuse(false);
    GpuTimings drawn = sc.best_of(r, t);
    r.set_ground_reuse(true);
    GpuTimings kept = sc.best_of(r, t);
    std::printf("\nHeld frames at 64 steps: %.2f ms keeping last frame's ground, %.2f ms drawing it every frame "
                "(%.2fx the full frame's speed against %.2fx).\n",
                kept.total_ms, drawn.total_ms, per_pass[0].total_ms / kept.total_ms, per_pass[0].total_ms / drawn.total_ms);
  }
  std::cout << "\nPasses at 64 steps (ms; full | temporal):";
  const std::vector<std::pair<std::string, double>> passes[2] = {per_pass[0].passes, per_pass[1].passes};
  print_passes(passes, 1.0);
}

// 3. Motion cost, at t = 60 s. First the seed's own measure (its abstract: "no more than 10%
// increase ... compared to the cloud movement algorithm without the use of flow-map"): clouds
// moved by the wind alone against the wind and the flow map. Then the whole motion against
// still clouds: on one lighting path (per-sample light march, thesis skipping, which moving
// layers always take), and with the defaults, where moving clouds lose the still frame's light
// volume and fine distance field.
void motion_cost_table(GlRenderer& r, const Scene& sc) {
  // Each frame with the distance field the viewer fits to it (fit_distance_field, as the window
  // and headless loops do): a still frame's field does not cover the motion's up flow, and
  // without the refit the moving frame would skip by the padded grid's one cell.
  auto frame_ms = [&](const RenderSettings& s) {
    PreparedVolume fitted = sc.vol;
    fit_distance_field(fitted, s);
    r.set_distance_field(fitted);
    double ms = best_ms(r, fitted, s, sc.cam, sc.sun, sc.a.w, sc.a.h, sc.a.repeat);
    r.set_distance_field(sc.vol);
    return ms;
  };
  std::printf("\n| motion at 60 s | without ms | with ms | cost |\n|---|---:|---:|---:|\n");
  for (int row = 0; row < 3; ++row) {
    RenderSettings with_it = sc.base;
    with_it.time = 60;
    if (row < 2) {
      with_it.light_volume = false;
      with_it.skipping = Skipping::Thesis;
    }
    RenderSettings without = with_it;
    if (row == 0) {
      without.motion.flow_up = 0;
      without.motion.flow_forward = 0;
    } else {
      without.motion.wind_speed = 0;
      without.motion.flow_speed = 0;
    }
    const double a = frame_ms(without), b = frame_ms(with_it);
    const char* what[] = {"flow map: wind + flow map against wind alone (the seed's measure; per-sample light march, thesis skipping)",
                          "wind + flow map against still clouds (the same path)",
                          "wind + flow map against still clouds (defaults: still frames use the light volume and distance field)"};
    std::printf("| %s | %.2f | %.2f | %+.1f%% |\n", what[row], a, b, 100.0 * (b / a - 1.0));
  }
}

// The moving track's sums over its measured frames.
struct TrackSums {
  double sum_rmse = 0, max_rmse = 0;
  double sum_full_ms = 0, sum_temporal_ms = 0, min_speedup = 1e300;  // the GPU time of each frame
  int max_ghosts = 0, measured = 0;
  long sum_ghosts = 0;
  // Every pass's time summed over the frames that move (full | temporal; not the first measured
  // frame, the full renderer's first, which builds its tables), in order of first run.
  int moved = 0;
  std::vector<std::pair<std::string, double>> pass_sums[2];

  static void add_passes(const GpuTimings& g, std::vector<std::pair<std::string, double>>& sums) {
    for (const auto& [name, ms] : g.passes) {
      auto it = std::find_if(sums.begin(), sums.end(), [&](const auto& e) { return e.first == name; });
      if (it == sums.end()) sums.push_back({name, ms});
      else it->second += ms;
    }
  }
  void add(double e, int g, const GpuTimings& tf, const GpuTimings& tt, bool moving) {
    sum_rmse += e, max_rmse = std::max(max_rmse, e);
    sum_ghosts += g, max_ghosts = std::max(max_ghosts, g);
    ++measured;
    sum_full_ms += tf.total_ms, sum_temporal_ms += tt.total_ms;
    min_speedup = std::min(min_speedup, tf.total_ms / tt.total_ms);
    if (moving) add_passes(tf, pass_sums[0]), add_passes(tt, pass_sums[1]), ++moved;
  }
  void print(int w, int h) const {
    std::printf("\n| moving track (%d frames: pan 0.5 deg, wind 15 m/s, 1 s per frame) | mean | worst |\n|---|---:|---:|\n| RMSE (display) | %.4f | %.4f |\n"
                "| ghost pixels (> 0.1) | %.1f (%.2f%%) | %d (%.2f%%) |\n"
                "| frame speed-up while moving (full ms / temporal ms, one run each) | %.2fx (%.2f / %.2f) | %.2fx |\n",
                measured, sum_rmse / measured, max_rmse, double(sum_ghosts) / measured,
                100.0 * double(sum_ghosts) / measured / (w * h), max_ghosts, 100.0 * max_ghosts / (w * h),
                sum_full_ms / sum_temporal_ms, sum_full_ms / measured, sum_temporal_ms / measured, min_speedup);
    std::cout << "\nPasses along the moving track (mean ms per frame over the " << moved
              << " frames that move; full | temporal):";
    print_passes(pass_sums, std::max(moved, 1));
  }
};

// 2. The moving track: 16 still frames to converge, then a pan of 0.5 degrees per frame with the
// wind at 15 m/s and 1 s per frame (the clouds visibly drift).
void moving_track(GlRenderer& r, const Scene& sc) {
  const int w = sc.a.w, h = sc.a.h;
  GlRenderer full{ShaderSource(sc.a.shader_dir)};
  full.set_volume(sc.vol);
  std::ofstream csv;
  if (!sc.a.csv_path.empty()) {
    csv.open(sc.a.csv_path);
    csv << "frame,rmse,ghost_pixels,full_ms,temporal_ms\n";
  }
  TrackSums sums;
  for (int f = 0; f < 16 + sc.a.track_frames; ++f) {
    int moving = std::max(0, f - 16);
    RenderSettings s = sc.base;
    s.motion.wind_speed = 15;
    s.frame = f;
    s.time = moving * 1.0;
    RenderSettings t = s;
    t.temporal = true;
    Camera c = orbit(sc.vol, moving * 0.5, double(w) / h);
    GpuTimings tt, tf;
    r.render(make_frame(sc.vol, t, c, sc.sun, w, h), &tt);
    if (f < 16) continue;
    full.render(make_frame(sc.vol, s, c, sc.sun, w, h), &tf);
    Image a = r.read_back().display, b = full.read_back().display;
    double e = rmse(a, b);
    int g = ghosts(a, b, 0.1);
    sums.add(e, g, tf, tt, moving > 0);
    if (csv) csv << moving << "," << e << "," << g << "," << tf.total_ms << "," << tt.total_ms << "\n";
  }
  sums.print(w, h);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kUsage;
    return 1;
  }
  Args a;
  if (!parse_args(argc, argv, a)) return 1;
  try {
    HeadlessContext ctx;
    Scene sc{a, {}, {}, {}, {}};
    for (const std::string& kv : a.sets) apply_setting(sc.base, kv);  // every configuration starts from these
    sc.vol = open_input(a.input, sc.base);
    sc.cam = default_camera(sc.vol, 60, double(a.w) / a.h);
    sc.sun = default_sun(sc.cam);
    GlRenderer r{ShaderSource(a.shader_dir)};
    r.set_volume(sc.vol);
    std::cout << "# " << ctx.description() << ", " << a.w << "x" << a.h << ", best of " << a.repeat << "\n\n";
    still_table(r, sc);
    motion_cost_table(r, sc);
    moving_track(r, sc);
  } catch (const std::exception& e) {
    std::cerr << "bench_temporal: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
