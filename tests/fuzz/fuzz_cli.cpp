// libFuzzer target for the command-line value parsers: --set (through the preset reader),
// --region, number lists (--at, --period, --camera...), sizes (--max-memory), integers (--seed), and
// a sequence's --frames, --fps and frame-file pattern. The first byte picks the parser (248 and up:
// the sequence parsers, so the older corpus keeps its meaning); the rest is the flag's text.
#include <cstdint>
#include <string>

#include "cloudgen/cli_parse.h"
#include "cloudgen/preset.h"
#include "cloudgen/sequence.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string s(reinterpret_cast<const char*>(data + 1), size - 1);
  return fuzz::guarded([&] {
    switch (data[0] >= 248 ? 5 + data[0] % 3 : data[0] % 5) {
      case 0: {
        cloudgen::Preset p = cloudgen::parse_preset("{\"resolution\": [16, 16, 16]}", "fuzz.json", {s});
        (void)p;
        break;
      }
      case 1: {
        const cloudgen::Region r = cloudgen::parse_region(s, {{64, 32, 64}});
        for (int a = 0; a < 3; ++a)
          if (r.extent[a] < 1 || uint64_t(r.origin[a]) + r.extent[a] > (a == 1 ? 32u : 64u)) __builtin_trap();
        break;
      }
      case 2: (void)cloudgen::parse_number_list(s, "--at", 1, 3); break;
      case 3: (void)cloudgen::parse_bytes(s, "--max-memory"); break;
      case 4:
        if (cloudgen::parse_uint(s, "--seed", cloudgen::kMaxSeed) > cloudgen::kMaxSeed) __builtin_trap();
        break;
      case 5: {
        const cloudgen::FrameRange r = cloudgen::parse_frames(s);
        if (r.first < 0 || r.last < r.first || r.last > cloudgen::kMaxFrameNumber || r.count() > cloudgen::kMaxSequenceFrames)
          __builtin_trap();
        break;
      }
      case 6: {
        const double fps = cloudgen::parse_fps(s);
        if (!(fps > 0 && fps <= 1000)) __builtin_trap();
        break;
      }
      case 7: {
        const std::string p = cloudgen::frame_path(s, 123);
        // The number replaces a run of '#' zero-padded to the run's length: never shorter, and a
        // name without a run comes back unchanged.
        if (p.size() < s.size() || (!cloudgen::has_frame_pattern(s) && p != s)) __builtin_trap();
        break;
      }
    }
  });
}
