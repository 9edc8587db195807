// One viewing session, the steps the command line, the window and the bench share: open the input,
// fit the distance field to a frame's settings, upload to the GL renderer, make the frame.
#pragma once
#include <memory>
#include <string>

#include "cloudviewer/frame.h"
#include "cloudviewer/gl_renderer.h"
#include "cloudviewer/headless_context.h"
#include "cloudviewer/prepared_volume.h"
#include "cloudviewer/settings.h"

namespace cloudviewer {

class Session {
 public:
  /// Opens `input` (open_input, a preset generated as `preset` says): a bad input fails here,
  /// before any OpenGL.
  Session(const std::string& input, const RenderSettings& s, uint32_t lod_level = 0, PresetSource preset = {});
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const PreparedVolume& volume() const { return vol_; }

  /// Headless: an EGL context of its own, then start_renderer. Returns the context's description.
  const std::string& start_headless(const std::string& shader_dir);
  /// The GL renderer in the current context (headless, or a window's), with the volume uploaded.
  GlRenderer& start_renderer(const std::string& shader_dir);
  /// Drops the renderer (and the headless context): a window ends it before its context goes.
  void stop_renderer();
  /// The renderer, or null before start_renderer (the CPU backends).
  GlRenderer* renderer() const { return renderer_.get(); }

  /// Opens the input again (at the same level of detail, the preset's sets as they are now) and
  /// uploads it (the window's reload, an --edit); the old volume stays on failure. `timing`: where
  /// the time went, the upload's in `upload_s`.
  void reopen(const std::string& input, const RenderSettings& s, InputTiming* timing = nullptr, double* upload_s = nullptr);
  /// Shows `v` from now on and uploads it: a volume opened elsewhere (off the GL thread, with
  /// lod_level() and preset()). With a noise cache the old volume's memory is kept for the next.
  void adopt(PreparedVolume v);
  /// How a preset input is generated: an edit adds to its sets, then reopen.
  PresetSource& preset() { return preset_; }
  const PresetSource& preset() const { return preset_; }
  uint32_t lod_level() const { return lod_level_; }
  /// The INPUT as given.
  const std::string& input() const { return input_; }
  /// A preset INPUT: checks KEY=VALUE (a preset key, as `cloudgen generate --set` spells it) against
  /// the preset with the edits so far and adds it to them (in place of an earlier value of the same
  /// key); the caller regenerates (reopen, or the
  /// window's worker). What the panel and `--edit` call. InputError, nothing changed, on a bad edit.
  void edit_preset(const std::string& assignment);
  /// A preset INPUT: writes it with the edits so far to `target` (cloudgen::save_preset_as: atomic,
  /// never into the shipped presets, not over the input unless `replace_input`). Returns the text.
  std::string save_preset_as(const std::string& target, bool replace_input = false) const;
  /// Uploads `v` (the volume, or a copy of it at other occupancy and field settings) unless it is
  /// the one the renderer holds.
  void show(const PreparedVolume& v);
  /// Fits the volume's distance field to the frame's erosion and motion (fit_distance_field); the
  /// renderer gets the new field.
  void fit(const RenderSettings& s);
  /// The frame's parameter block (make_frame) over the volume.
  FrameSetup frame(const RenderSettings& s, const Camera& cam, const Sun& sun, int width, int height) const;
  /// make_frame_or_keep over the volume: a choice the volume refuses goes back to `good`.
  FrameSetup frame_or_keep(RenderSettings& s, RenderSettings& good, const Camera& cam, const Sun& sun, int width,
                           int height, std::string& refused) const;

 private:
  std::string input_;
  PreparedVolume vol_;
  uint32_t lod_level_ = 0;  // the .vdb level of detail drawn (reopen keeps it)
  PresetSource preset_;
  std::vector<float> spare_rgba_;  // the dense channels of the volume an edit replaced (preset_.spare_rgba)
  std::unique_ptr<HeadlessContext> context_;  // declared first: it outlives the renderer
  std::unique_ptr<GlRenderer> renderer_;
  const PreparedVolume* uploaded_ = nullptr;  // what the renderer holds
};

}  // namespace cloudviewer
