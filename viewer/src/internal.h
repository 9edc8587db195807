// Pieces of the command line shared by app.cpp, bench.cpp and window.cpp (not installed).
#pragma once
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
  std::vector<std::string> sets;
  std::string out;
  std::string backend = "gl";
  std::string shader_dir;
  std::string mie_table;
  std::string bench;
  std::string csv;
  int bench_reference = 0;  ///< CPU reference step count for RMSE columns (0 = none)
  int bench_repeat = 3;
  RenderSettings settings;  ///< after --set
  cloudgen::View view;      ///< the input's preset/metadata view (default_view.h)
};

/// Camera from --camera or the default framing; sun from --sun or behind the viewer.
Camera resolve_camera(const Options& o, const PreparedVolume& vol, int width, int height);
Sun resolve_sun(const Options& o, const Camera& cam);

int run_bench(const Options& o, const PreparedVolume& vol, std::ostream& out, std::ostream& err);
int run_window(const Options& o, std::ostream& out, std::ostream& err);

}  // namespace cloudviewer
