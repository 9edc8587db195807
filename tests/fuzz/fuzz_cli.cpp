// libFuzzer target for the command-line value parsers: --set (through the preset reader),
// --region, number lists (--at, --period, --camera...), sizes (--max-memory) and integers (--seed).
// The first byte picks the parser; the rest is the flag's text.
#include <cstdint>
#include <string>

#include "cloudgen/cli_parse.h"
#include "cloudgen/preset.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string s(reinterpret_cast<const char*>(data + 1), size - 1);
  return fuzz::guarded([&] {
    switch (data[0] % 5) {
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
    }
  });
}
