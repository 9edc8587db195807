// libFuzzer target for the viewer's benchmark track reader (--bench TRACK.json): everything the
// bench does before OpenGL. A track is accepted or refused with InputError naming the pointer.
#include <cstdint>
#include <string>

#include "../../viewer/src/internal.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const cloudviewer::PreparedVolume vol =
      cloudviewer::prepare_volume(cloudviewer::synthetic_volume("sphere"), 8);
  const std::string text(reinterpret_cast<const char*>(data), size);
  return fuzz::guarded([&] {
    cloudviewer::Options o;
    o.width = 32, o.height = 18;
    const cloudviewer::BenchPlan plan = cloudviewer::parse_track(text, "fuzz.json", o, vol);
    if (plan.frames.empty() || plan.configs.size() != plan.settings.size()) __builtin_trap();
  });
}
