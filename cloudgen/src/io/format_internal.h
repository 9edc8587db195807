// Helpers shared by the format files (raw_io.cpp, ktx2_io.cpp, atlas_io.cpp, formats.cpp).
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cloudgen/io.h"

namespace cloudgen::detail {

using json = nlohmann::json;

/// Sidecar description of a volume written as texels of format `t` (raw and atlas sidecars).
json describe_json(const Volume& v, Texel t);

/// Fills v.density and the first `channels - 1` detail channels from packed texels.
void unpack_texels(Volume& v, const uint8_t* data, Texel t, int channels);

/// Stages a JSON document as a text file.
void stage_json(OutputBatch& batch, const std::string& path, const json& j);

/// Overflow-checked product of three sizes; false if it exceeds `limit`.
bool checked_volume(uint64_t x, uint64_t y, uint64_t z, uint64_t limit, uint64_t* out);

/// Largest edge and voxel count any reader accepts (a 65536^3 volume would be 2^48 voxels;
/// real inputs are far below 2^34).
inline constexpr uint32_t kMaxEdge = 65536;
inline constexpr uint64_t kMaxVoxels = uint64_t(1) << 34;

/// Reads the typed fields of sidecars and KTX2 key/value data, naming the field in every error.
class FieldReader {
 public:
  FieldReader(const json& j, std::string where) : j_(j), where_(std::move(where)) {}
  bool has(const char* key) const { return j_.is_object() && j_.contains(key); }
  const json& at(const char* key) const;
  std::string string(const char* key) const;
  bool boolean(const char* key, bool def) const;
  double number(const char* key, double def, double lo, double hi) const;
  uint32_t integer(const char* key, uint32_t def, uint32_t lo, uint32_t hi) const;
  std::array<uint32_t, 3> ivec3(const char* key, uint32_t lo, uint32_t hi) const;
  std::array<double, 3> vec3(const char* key, double lo, double hi) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
  double number_value(const json& v, const std::string& key, double lo, double hi) const;
  uint32_t integer_value(const json& v, const std::string& key, uint32_t lo, uint32_t hi) const;
  const json& j_;
  std::string where_;
};

}  // namespace cloudgen::detail
