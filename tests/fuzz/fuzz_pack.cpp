// libFuzzer target for the texture pack's readers (cloudgen/texture_pack.h): pack.json's validation
// and the KTX2 mip-chain reader (every level's offset and length against the file), with the check
// that each mip is the box filter of the level above. An input starting with the KTX2 identifier
// goes to the KTX2 reader, anything else to pack.json's.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "cloudgen/texture_pack.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const uint8_t kId[4] = {0xAB, 'K', 'T', 'X'};
  if (size >= 4 && std::memcmp(data, kId, 4) == 0) {
    const std::vector<uint8_t> bytes(data, data + size);
    return fuzz::guarded([&] {
      const cloudgen::MipTexture t = cloudgen::parse_ktx2_mips(bytes, "fuzz.ktx2", uint64_t(64) << 20);
      if (t.levels.empty() || t.channels < 1 || t.channels > 4) __builtin_trap();
      for (size_t l = 0; l < t.levels.size(); ++l) {
        const auto d = cloudgen::mip_dims(t.dims, uint32_t(l));
        if (t.levels[l].size() != size_t(d[0]) * d[1] * d[2] * size_t(t.channels)) __builtin_trap();
        if (l) (void)cloudgen::box_downsample(t.levels[l - 1], cloudgen::mip_dims(t.dims, uint32_t(l - 1)), t.channels);
      }
    });
  }
  const std::string text(reinterpret_cast<const char*>(data), size);
  return fuzz::guarded([&] {
    (void)cloudgen::is_pack_json(text);
    const cloudgen::PackDescription d = cloudgen::parse_pack_json(text, "fuzz/pack.json");
    if (d.textures.size() != 4) __builtin_trap();
    for (const auto& t : d.textures)
      if (t.mips < 1 || t.mips > cloudgen::full_mip_count(t.dims) || t.ktx2.find('/') != std::string::npos) __builtin_trap();
  });
}
