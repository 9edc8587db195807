// Pieces of the command line shared by app.cpp, bench.cpp and window.cpp (not installed).
#pragma once
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "cloudgen/view.h"

namespace cloudviewer {

struct Options {
  std::string input;
  bool headless = false;
  int width = 0, height = 0;
  std::optional<Camera> camera;
  double fov = 60;
  std::optional<Sun> sun;
  std::vector<std::string> sets;         ///< --set render.*, atmosphere.*, motion.* (run() sorts them out)
  std::vector<std::string> preset_sets;  ///< --set of a preset INPUT's own keys (threshold=0.4)
  std::vector<std::string> edits;        ///< --edit: preset keys applied one after another, headless
  std::string out;
  std::string backend = "gl";
  std::string shader_dir;
  std::string mie_table;
  std::string bench;
  std::string csv;
  bool stats = false;  ///< --stats: per-pass GPU times and per-LUT precompute times
  int bench_reference = 0;  ///< CPU reference step count for RMSE columns (0 = none)
  int bench_repeat = 3;
  int frames = 1;           ///< headless: frames to render (--frames)
  int spp = 64;             ///< --backend pathtrace: paths per pixel
  double fps = 24;          ///< time step 1/fps between frames (0: time stands still)
  RenderSettings settings;  ///< after --set (and --time)
  cloudgen::View view;      ///< the input's preset/metadata view (default_view.h)
};

/// Tileable fBm in [0, 1] (libnoise3d Perlin fBm, mean 0.5, std ~0.13) for the synthetic volumes
/// and the coverage map; `period` in lattice cells on every axis.
double tileable_fbm(double x, double y, double z, int period, int octaves, uint32_t seed);

/// Camera from --camera or the default framing; sun from --sun or behind the viewer.
Camera resolve_camera(const Options& o, const PreparedVolume& vol, int width, int height);
Sun resolve_sun(const Options& o, const Camera& cam);
/// A .vdb with levels of detail: the level its default or given camera and render.dense_budget call
/// for (choose_lod in cloudviewer/lod.h), said on `out`, with render.sigma_t pinned to the full
/// resolution's extinction when it is drawn coarser. 0 for other inputs.
uint32_t choose_input_lod(Options& o, std::ostream& out);

/// A benchmark camera track (viewer/tracks/default.json): the frames, the configurations and
/// their settings.
struct TrackFrame {
  std::string name, view;  ///< view class: below, inside, above (or what the track says)
  Camera camera;
  std::vector<std::string> sets;  ///< the key's own render.KEY=VALUE, applied after the configuration's
};
struct Config {
  std::string name;
  std::vector<std::string> sets;
};
struct BenchPlan {
  std::vector<TrackFrame> frames;
  std::vector<Config> configs;
  std::vector<RenderSettings> settings;  ///< o.settings with each configuration's sets applied
  Sun fixed_sun;
  bool has_sun = false;
};
/// Parses and checks a track (`where` names it in messages): every field typed and ranged,
/// InputError naming the JSON pointer otherwise. Everything --bench does before OpenGL.
BenchPlan parse_track(const std::string& text, const std::string& where, const Options& o, const PreparedVolume& vol);
class Session;
/// --bench over the session's volume (opened; the bench starts its renderer).
int run_bench(const Options& o, Session& session, std::ostream& out, std::ostream& err);
int run_window(const Options& o, std::ostream& out, std::ostream& err);

}  // namespace cloudviewer
