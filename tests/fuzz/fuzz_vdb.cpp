// libFuzzer target for the VDB reading path up to the dense volume: our layout check, OpenVDB's
// reader, the density/detail densifying and `cloudgen info`'s description. The bytes go to a file
// in memory (/dev/shm) because OpenVDB reads files by name.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "cloudgen/io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/dev/shm/cloud-fuzz-" + std::to_string(::getpid()) + ".vdb";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  fuzz::guarded([&] { (void)cloudgen::read_vdb(path, uint64_t(64) << 20); });
  fuzz::guarded([&] { (void)cloudgen::describe_vdb(path); });
  std::remove(path.c_str());
  return 0;
}
