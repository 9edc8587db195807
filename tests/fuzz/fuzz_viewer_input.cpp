// libFuzzer target for the viewer's input dispatch (open_input: a preset .json, a raw texture's
// sidecar .json, .ktx2 or .vdb, then densifying and the occupancy grid): everything before OpenGL.
// The first byte picks the file type; the rest is the file. VDB files are left to fuzz_vdb, which
// only replays its corpus: mutating them reaches a heap overflow inside OpenVDB 10's reader.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "cloudgen/preset.h"
#include "cloudviewer/scene.h"
#include "cloudviewer/settings.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {".json", ".ktx2"};
  const std::string ext = kExt[data[0] % 2];
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (ext == ".json") {
    // A valid preset is generated: keep that small so one input stays well under the time limit.
    try {
      const cloudgen::Preset p = cloudgen::parse_preset(text, "fuzz.json");
      if (uint64_t(p.resolution[0]) * p.resolution[1] * p.resolution[2] > 48 * 48 * 48) return 0;
    } catch (...) {
    }
  }
  const std::string path = "/dev/shm/cloud-fuzz-input-" + std::to_string(::getpid()) + ext;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  fuzz::guarded([&] {
    cloudviewer::RenderSettings s;
    const cloudviewer::PreparedVolume v = cloudviewer::open_input(path, s);
    if (v.dims[0] < 1 || v.dims[1] < 1 || v.dims[2] < 1) __builtin_trap();
  });
  std::remove(path.c_str());
  return 0;
}
