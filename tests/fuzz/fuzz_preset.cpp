// libFuzzer target for the preset reader: any byte string must either parse into a valid preset
// or be rejected with InputError / InvalidParameter; never crash, hang or leak.
//   scripts/test.sh builds it into build-fuzz/; build-fuzz/bin/fuzz_preset tests/fuzz/preset
#include <cstdint>
#include <string>

#include "cloudgen/channel.h"
#include "cloudgen/generate.h"
#include "cloudgen/preset.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  return fuzz::guarded([&] {
    cloudgen::Preset p = cloudgen::parse_preset(text, "fuzz.json");
    // A preset that validated must be usable: the noise parameters of every channel are valid.
    for (int c = 0; c < 4; ++c)
      if (p.channels[c].enabled) noise3d::validate(cloudgen::channel_params(p, c));
    (void)cloudgen::memory_estimate(p, true);
  });
}
