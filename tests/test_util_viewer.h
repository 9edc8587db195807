// Helpers shared by the viewer's test files (beside test_util.h, which the cloudgen-only build
// uses without the viewer): the one headless GL context, a GL render of a frame, render settings
// from key=value strings, the default framing, and `cloudviewer ARGS` run in process.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cloudviewer/app.h"
#include "cloudviewer/renderer.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "test_util.h"

namespace testutil {

/// The test binary's one headless context (EGL), made current. A failure to create it throws
/// (GlError): a failure, not a skip, since CI runs on this kind of machine.
inline cloudviewer::HeadlessContext& gl_context() {
  static std::unique_ptr<cloudviewer::HeadlessContext> ctx = std::make_unique<cloudviewer::HeadlessContext>();
  ctx->make_current();
  return *ctx;
}

/// cloudviewer::synthetic_volume(kind), made once per kind in a test process: many tests start
/// from the same few volumes, and making one (noise over 442k voxels) costs seconds under the
/// sanitizers. A const reference: copy it to change it.
inline const cloudgen::Volume& synthetic(const std::string& kind) {
  static std::map<std::string, cloudgen::Volume> made;
  auto it = made.find(kind);
  if (it == made.end()) it = made.emplace(kind, cloudviewer::synthetic_volume(kind)).first;
  return it->second;
}

/// One frame of `vol` through the test process's one GL renderer, read back. It is kept across
/// frames, volumes and settings as the window keeps its one renderer, so every frame also checks
/// that the renderer's caches (LUTs, light volume, shadow map, programs) follow what changed; a
/// fresh renderer per frame cost most of the GL tests' time in recomputing the same LUTs.
inline cloudviewer::FrameImages render_gl(const cloudviewer::PreparedVolume& vol, const cloudviewer::FrameSetup& f) {
  gl_context();
  static cloudviewer::GlRenderer r{cloudviewer::ShaderSource()};
  r.set_volume(vol);
  r.render(f);
  return r.read_back();
}

/// One frame of `vol` on GL (render_gl) or on the CPU reference.
inline cloudviewer::FrameImages render_on(bool on_gl, const cloudviewer::PreparedVolume& vol,
                                          const cloudviewer::FrameSetup& f) {
  return on_gl ? render_gl(vol, f) : cloudviewer::render_cpu(vol, f);
}

/// The render tests' frame: 160x90, or 64x36 under the sanitizers (sized, test_util.h).
inline const int kFrameW = sized(160, 64), kFrameH = sized(90, 36);

/// A small deterministic generator for the tests' random cases: the next 24-bit value of `h`.
inline uint32_t lcg(uint32_t& h) { return (h = h * 1664525u + 1013904223u) >> 8; }

/// Primary-march loop trips summed over a frame rendered with render.output=iterations (each
/// pixel's count in the red channel of the linear image).
inline double loop_trips_sum(const cloudviewer::FrameImages& iterations) {
  double sum = 0;
  for (size_t i = 0; i < iterations.linear.rgba.size(); i += 4) sum += iterations.linear.rgba[i];
  return sum;
}

/// Default render settings with each "render.key=value" applied in order.
inline cloudviewer::RenderSettings with(std::initializer_list<const char*> sets) {
  cloudviewer::RenderSettings s;
  for (const char* a : sets) cloudviewer::apply_setting(s, a);
  return s;
}

/// A w x h frame from the default camera (60 degrees) and the default sun.
inline cloudviewer::FrameSetup frame_for(const cloudviewer::PreparedVolume& vol, const cloudviewer::RenderSettings& s,
                                         int w = 160, int h = 90) {
  cloudviewer::Camera cam = cloudviewer::default_camera(vol, 60, double(w) / h);
  return cloudviewer::make_frame(vol, s, cam, cloudviewer::default_sun(cam), w, h);
}

/// `cloudviewer ARGS` in process (cloudviewer::run_cli); returns the exit code, and what it wrote
/// to stderr and stdout when asked.
inline int run(std::vector<std::string> args, std::string* err_text = nullptr, std::string* out_text = nullptr) {
  args.insert(args.begin(), "cloudviewer");
  std::ostringstream out, err;
  const int code = cloudviewer::run_cli(args, out, err);
  if (err_text) *err_text = err.str();
  if (out_text) *out_text = out.str();
  return code;
}

}  // namespace testutil
