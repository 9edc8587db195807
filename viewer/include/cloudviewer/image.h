// Float RGBA images, PNG/EXR output and comparison metrics. Rows are stored bottom-up (OpenGL
// window order); the writers flip.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace cloudviewer {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;  ///< 4 floats per pixel, row 0 at the bottom
  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(size_t(w) * h * 4, 0.f) {}
  float* at(int x, int y) { return &rgba[(size_t(y) * width + x) * 4]; }
  const float* at(int x, int y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

/// 8-bit sRGB PNG of values already encoded for display (clamped to [0,1]). Throws IoError-like Error.
void write_png(const std::string& path, const Image& img);
/// Linear half-float RGBA OpenEXR.
void write_exr(const std::string& path, const Image& img);
/// Reads an 8-bit PNG into [0,1] floats (for tests and tools).
Image read_png(const std::string& path);
/// Reads an RGBA OpenEXR.
Image read_exr(const std::string& path);

/// Writes by extension (.png display image, .exr linear image).
void write_image(const std::string& path, const Image& display, const Image& linear);
/// Several images of one result (e.g. the path tracer's image and its standard error), each by its
/// extension, all or nothing: a failed write leaves every earlier file as it was.
struct ImageFile {
  std::string path;
  const Image* display;
  const Image* linear;
};
void write_images(const std::vector<ImageFile>& files);

/// Images of several results (the frames of a sequence) staged one after another and published
/// together by commit(): all or none, as `cloudgen generate` publishes its outputs. Each image is
/// encoded into its temporary when staged, so the batch holds no pixels.
class ImageBatch {
 public:
  ImageBatch();
  ~ImageBatch();
  ImageBatch(const ImageBatch&) = delete;
  ImageBatch& operator=(const ImageBatch&) = delete;
  void stage(const std::vector<ImageFile>& files);
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ImageStats {
  int nonfinite = 0;      ///< NaN or inf values
  double min = 0, max = 0, mean = 0, stddev = 0;  ///< over RGB
};
ImageStats image_stats(const Image& img);

/// Root mean square error over RGB.
double rmse(const Image& a, const Image& b);
/// PSNR in dB over RGB with the given peak (1 for display images).
double psnr(const Image& a, const Image& b, double peak = 1.0);
/// Largest absolute RGB difference.
double max_abs_diff(const Image& a, const Image& b);
/// |a - b| * gain per channel, for diff images.
Image diff_image(const Image& a, const Image& b, double gain);

}  // namespace cloudviewer
