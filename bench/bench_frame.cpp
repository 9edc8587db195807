// The CPU's share of a frame: make_frame (frame.cpp), which the viewer runs before every draw. It
// is per-frame work a GPU does not hide: on a GPU the march takes milliseconds, so a setup of a few
// more would show in the frame rate. Still and moving frames (--time 60: the motion table, and the
// moved occupancy grid where a reader needs it), under each skipping scheme.
// Usage: bench_frame [VOLUME] [google-benchmark flags]; VOLUME as the viewer takes it (default
// synthetic:noise). docs/viewer-speed.md has the figures and the command.
#include <benchmark/benchmark.h>

#include <string>

#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"

using namespace cloudviewer;

namespace {

std::string g_input = "synthetic:noise";

RenderSettings settings_at(double time, Skipping skipping) {
  RenderSettings s;
  s.time = time;
  s.skipping = skipping;
  return s;
}

// The volume as the viewer holds it at `time`: its distance field fitted to the motion
// (fit_distance_field, as the window and the bench do), once per time.
const PreparedVolume& volume(double time) {
  static const PreparedVolume still = open_input(g_input, RenderSettings{});
  static const PreparedVolume moving = [] {
    PreparedVolume v = still;
    fit_distance_field(v, settings_at(60, Skipping::Distance));
    return v;
  }();
  return time > 0 ? moving : still;
}

// Args: time (s), skipping (0 none, 1 thesis, 2 distance).
void BM_MakeFrame(benchmark::State& state) {
  const RenderSettings s = settings_at(double(state.range(0)), Skipping(state.range(1)));
  const PreparedVolume& vol = volume(s.time);
  const Camera cam = default_camera(vol, 60, 16.0 / 9.0);
  const Sun sun = default_sun(cam);
  FrameSetup f;
  for (auto _ : state) {
    f = make_frame(vol, s, cam, sun, 1920, 1080);
    benchmark::DoNotOptimize(f);
  }
  state.counters["moved_grid_cells"] = double(f.moved_occupancy.size());
  state.counters["skip"] = f.params.occupancy_skip;
  state.counters["stretch"] = f.params.motion_stretch;
  state.SetLabel(std::string(s.time > 0 ? "moving" : "still") +
                 (s.skipping == Skipping::None ? ", skip none" : s.skipping == Skipping::Thesis ? ", thesis" : ", distance"));
}
BENCHMARK(BM_MakeFrame)
    ->ArgsProduct({{0, 60}, {0, 1, 2}})
    ->ArgNames({"time", "skipping"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (argc > 1) g_input = argv[1];
  volume(60);  // open and fit outside the timing
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
