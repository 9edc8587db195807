#include "app/session.h"

#include <chrono>
#include <utility>

#include "cloudviewer/distance_field.h"
#include "cloudviewer/errors.h"
#include "cloudviewer/input.h"
#include "cloudviewer/memory_budget.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/errors.h"
#include "cloudgen/preset.h"
#include "cloudgen/preset_save.h"
#endif

namespace cloudviewer {

Session::Session(const std::string& input, const RenderSettings& s, uint32_t lod_level, PresetSource preset)
    : input_(input), vol_(open_input(input, s, lod_level, preset)), lod_level_(lod_level), preset_(std::move(preset)) {
  if (preset_.noise_cache) {
    preset_.spare_rgba = &spare_rgba_;  // an edited preset reuses the memory
    // The first edit's too: its interleaved copy would otherwise fault in fresh pages (256 MiB at
    // 256^3, a third of that edit's prepare), so they are faulted in now, while the window opens,
    // when there is room for a second copy (an edit needs it then anyway).
    const uint64_t bytes = uint64_t(vol_.rgba.size()) * sizeof(float);
    if (bytes > 0 && bytes * 4 < available_memory_bytes()) spare_rgba_.assign(vol_.rgba.size(), 0.f);
  }
}

Session::~Session() { stop_renderer(); }

const std::string& Session::start_headless(const std::string& shader_dir) {
  context_ = std::make_unique<HeadlessContext>();
  start_renderer(shader_dir);
  return context_->description();
}

GlRenderer& Session::start_renderer(const std::string& shader_dir) {
  renderer_ = std::make_unique<GlRenderer>(ShaderSource(shader_dir));
  renderer_->set_volume(vol_);
  uploaded_ = &vol_;
  return *renderer_;
}

void Session::stop_renderer() {
  renderer_.reset();
  context_.reset();
  uploaded_ = nullptr;
}

void Session::edit_preset(const std::string& assignment) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  // A later value of the same key replaces the earlier one (a dragged slider makes many).
  const std::string key = assignment.substr(0, assignment.find('=') + 1);
  std::vector<std::string> sets;
  for (const std::string& s : preset_.sets)
    if (key.size() < 2 || s.rfind(key, 0) != 0) sets.push_back(s);
  sets.push_back(assignment);
  try {
    cloudgen::load_preset(input_, sets);  // the same check as loading: key, value, range, cross-checks
  } catch (const cloudgen::InputError& e) {
    throw InputError("edit " + assignment + ": " + e.what());
  }
  preset_.sets = std::move(sets);
#else
  throw InputError("edit " + assignment + ": this cloudviewer was built without the cloudgen library");
#endif
}

std::string Session::save_preset_as(const std::string& target, bool replace_input) const {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  return cloudgen::save_preset_as(input_, preset_.sets, target, replace_input);
#else
  (void)target, (void)replace_input;
  throw InputError("save preset as: this cloudviewer was built without the cloudgen library");
#endif
}

void Session::reopen(const std::string& input, const RenderSettings& s, InputTiming* timing, double* upload_s) {
  PreparedVolume v = open_input(input, s, lod_level_, preset_, timing);
  const auto t0 = std::chrono::steady_clock::now();
  adopt(std::move(v));
  if (upload_s) *upload_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void Session::adopt(PreparedVolume v) {
  std::vector<float> old = std::move(vol_.rgba);
  vol_ = std::move(v);
  if (renderer_) renderer_->set_volume(vol_), uploaded_ = &vol_;
  if (preset_.spare_rgba) spare_rgba_ = std::move(old);  // for the next edit (nothing draws it now)
}

void Session::show(const PreparedVolume& v) {
  if (renderer_ && &v != uploaded_) renderer_->set_volume(v), uploaded_ = &v;
}

void Session::fit(const RenderSettings& s) {
  if (fit_distance_field(vol_, s) && renderer_) renderer_->set_distance_field(vol_);
}

FrameSetup Session::frame(const RenderSettings& s, const Camera& cam, const Sun& sun, int width, int height) const {
  return make_frame(vol_, s, cam, sun, width, height);
}

FrameSetup Session::frame_or_keep(RenderSettings& s, RenderSettings& good, const Camera& cam, const Sun& sun,
                                  int width, int height, std::string& refused) const {
  return make_frame_or_keep(vol_, s, good, cam, sun, width, height, refused);
}

}  // namespace cloudviewer
