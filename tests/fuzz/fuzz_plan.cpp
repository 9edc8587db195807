// libFuzzer target for the farm plan reader (`cloudgen merge PLAN`, cloudgen/plan.h): the input is
// the plan's text. It is accepted or refused with InputError; an accepted plan must hold what
// merge relies on: plain tile file names, and regions that parse, lie inside the volume and
// cover it exactly.
#include <cstdint>
#include <string>

#include "cloudgen/plan.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  return fuzz::guarded([&] {
    const nlohmann::json plan = cloudgen::parse_plan(text, "fuzz.json");
    uint64_t covered = 0;
    for (const auto& t : plan["tiles"]) {
      const std::string file = t["file"].get<std::string>();
      if (file.empty() || file.find('/') != std::string::npos || file == "..") __builtin_trap();
      std::array<uint32_t, 3> lo, ext;
      if (!cloudgen::parse_region(t["region"].get<std::string>(), lo, ext)) __builtin_trap();
      uint64_t v = 1;
      for (int a = 0; a < 3; ++a) {
        if (uint64_t(lo[a]) + ext[a] > plan["resolution"][a].get<uint64_t>()) __builtin_trap();
        v *= ext[a];
      }
      covered += v;
    }
    const auto& r = plan["resolution"];
    if (covered != r[0].get<uint64_t>() * r[1].get<uint64_t>() * r[2].get<uint64_t>()) __builtin_trap();
  });
}
