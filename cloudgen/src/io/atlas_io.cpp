// Slice atlas: one tile per height level y (an x-z slice), tiles in row-major order, as Unreal's
// and Godot's 3D-texture importers expect (slice axis = the engine's up axis). PNG (RGBA8) or
// EXR (RGBA half), plus a JSON sidecar describing the layout.
#include <ImfHeader.h>
#include <ImfRgbaFile.h>
#include <ImfStdIO.h>
#include <png.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "cloudgen/io.h"
#include "io/format_internal.h"

namespace cloudgen {

namespace fs = std::filesystem;
using detail::json;

void write_atlas(const Volume& v, const std::string& path, Format f, OutputBatch& batch) {
  const uint32_t nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
  const uint32_t cols = uint32_t(std::ceil(std::sqrt(double(ny)))), rows = (ny + cols - 1) / cols;
  const uint32_t W = cols * nx, H = rows * nz;
  if (uint64_t(W) > 0x7fffffff / 4 || uint64_t(H) > 0x7fffffff / 4 || uint64_t(W) * H > (uint64_t(1) << 31))
    throw InputError(printable(path) + ": a " + std::to_string(W) + " x " + std::to_string(H) +
                     " atlas is too large for PNG/EXR readers; write a .raw or .ktx2 3D texture instead");
  const bool png = f == Format::AtlasPng;
  const std::vector<uint8_t> texels = pack_texels(v, png ? Texel::Rgba8 : Texel::Rgba16f);
  const size_t tb = png ? 4 : 8;
  std::vector<uint8_t> img(size_t(W) * H * tb, 0);
  for (uint32_t y = 0; y < ny; ++y)
    for (uint32_t z = 0; z < nz; ++z)
      std::memcpy(&img[((size_t(y / cols) * nz + z) * W + size_t(y % cols) * nx) * tb], &texels[v.index(0, y, z) * tb],
                  size_t(nx) * tb);
  batch.stage(path, [&](const std::string& tmp) {
    if (png) {
      png_image im;
      std::memset(&im, 0, sizeof im);
      im.version = PNG_IMAGE_VERSION;
      im.width = W, im.height = H, im.format = PNG_FORMAT_RGBA;
      // libpng checks fwrite, fflush and fclose here and reports the system's reason.
      if (!png_image_write_to_file(&im, tmp.c_str(), 0, img.data(), 0, nullptr))
        throw IoError(printable(path) + ": PNG write failed: " + im.message);
      png_image_free(&im);
    } else {
      // OpenEXR finishes a file in its destructor, where errors are swallowed: encode to memory,
      // then write the bytes with every write checked.
      std::string bytes;
      {
        Imf::StdOSStream os;
        {
          Imf::RgbaOutputFile out(os, Imf::Header(int(W), int(H)), Imf::WRITE_RGBA);
          out.setFrameBuffer(reinterpret_cast<const Imf::Rgba*>(img.data()), 1, W);
          out.writePixels(int(H));
        }
        bytes = os.str();
      }
      write_file_bytes(tmp, bytes.data(), bytes.size());
    }
  });
  json j = detail::describe_json(v, png ? Texel::Rgba8 : Texel::Rgba16f);
  j["file"] = fs::path(path).filename().string();
  j["layout"] = {{"slice_axis", "y (height): tile i holds the x-z slice at height y = i"},
                 {"tiles", {cols, rows}},
                 {"tile_size", {nx, nz}},
                 {"image_size", {W, H}},
                 {"order", "row-major, tile i at column i % tiles[0], row i / tiles[0]; pixel (x, row z)"}};
  detail::stage_json(batch, fs::path(path).replace_extension(".json").string(), j);
}

}  // namespace cloudgen
