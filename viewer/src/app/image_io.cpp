#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <functional>
#include <memory>

#include <unistd.h>

#include <ImfArray.h>
#include <ImfRgbaFile.h>
#include <png.h>

#include "cloudviewer/errors.h"
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
#include "cloudgen/io.h"
#endif
#include "cloudviewer/image.h"

namespace cloudviewer {

namespace {

// Writes through a temporary file renamed into place only when complete (cloudgen::atomic_write),
// so a failed write (full disk, no permission) leaves an existing file byte for byte.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& fill) {
#ifdef CLOUDVIEWER_HAS_CLOUDGEN
  cloudgen::atomic_write(path, fill);
#else
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    fill(tmp);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw IoError(path + ": cannot move the finished file into place: " + why);
  }
#endif
}

std::string system_reason(const char* fallback) { return errno ? std::strerror(errno) : fallback; }

// libpng's own messages ("Write Error") say nothing of the cause: the write callback keeps the
// system's errno from the failed fwrite, the error callback keeps libpng's text, and neither
// prints to stderr (the caller's exception carries the reason).
struct PngSink {
  FILE* fp = nullptr;
  int write_errno = 0;
  char message[160] = {0};
};

void png_sink_write(png_structp png, png_bytep data, png_size_t n) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  errno = 0;
  if (std::fwrite(data, 1, n, sink->fp) != n) {
    sink->write_errno = errno ? errno : EIO;
    png_error(png, "write failed");
  }
}

void png_sink_flush(png_structp png) { std::fflush(static_cast<PngSink*>(png_get_io_ptr(png))->fp); }

void png_sink_error(png_structp png, png_const_charp msg) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", msg ? msg : "libpng error");
  png_longjmp(png, 1);
}

void png_sink_warning(png_structp, png_const_charp) {}

void write_png_file(const std::string& path, const std::string& shown, const Image& img) {
  errno = 0;
  PngSink sink;
  sink.fp = std::fopen(path.c_str(), "wb");
  if (!sink.fp) throw IoError("cannot write '" + shown + "': " + system_reason("cannot open"));
  FILE* fp = sink.fp;
  // Everything with a destructor exists before setjmp: libpng's error longjmp skips destructors of
  // objects constructed after it (ASan found the row buffer leaking on a failed write).
  std::vector<png_byte> row(size_t(img.width) * 3);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, png_sink_error, png_sink_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    const std::string why = sink.write_errno ? std::strerror(sink.write_errno)
                            : sink.message[0] ? std::string("libpng: ") + sink.message
                                              : std::string("out of memory");
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
    throw IoError("cannot write '" + shown + "': " + why);
  }
  png_set_write_fn(png, &sink, png_sink_write, png_sink_flush);
  png_set_IHDR(png, info, png_uint_32(img.width), png_uint_32(img.height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = img.height - 1; y >= 0; --y) {  // bottom-up storage -> top-down file
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) {
        float v = img.at(x, y)[c];
        v = std::isfinite(v) ? std::clamp(v, 0.f, 1.f) : 0.f;
        row[size_t(x) * 3 + c] = png_byte(std::lround(v * 255.f));
      }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  // Buffered data reaches the disk at fflush/fclose: a full disk shows up here.
  errno = 0;
  bool ok = std::fflush(fp) == 0 && !std::ferror(fp);
  std::string why = system_reason("write error");
  if (std::fclose(fp) != 0 && ok) ok = false, why = system_reason("close failed");
  if (!ok) throw IoError("cannot write '" + shown + "': " + why);
}

}  // namespace

void write_png(const std::string& path, const Image& img) {
  write_atomically(path, [&](const std::string& tmp) { write_png_file(tmp, path, img); });
}

Image read_png(const std::string& path) {
  png_image im;
  std::memset(&im, 0, sizeof(im));
  im.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&im, path.c_str())) throw InputError("cannot read PNG '" + path + "'");
  im.format = PNG_FORMAT_RGBA;
  std::vector<png_byte> buf(PNG_IMAGE_SIZE(im));
  if (!png_image_finish_read(&im, nullptr, buf.data(), 0, nullptr)) throw InputError("cannot decode PNG '" + path + "'");
  Image img(int(im.width), int(im.height));
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 4; ++c)
        img.at(x, img.height - 1 - y)[c] = buf[(size_t(y) * im.width + x) * 4 + c] / 255.f;
  return img;
}

namespace {
void write_exr_file(const std::string& tmp, const std::string& path, const Image& img) {
    try {
      std::vector<Imf::Rgba> px(size_t(img.width) * img.height);
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
          const float* s = img.at(x, img.height - 1 - y);
          px[size_t(y) * img.width + x] = Imf::Rgba(s[0], s[1], s[2], s[3]);
        }
      Imf::RgbaOutputFile file(tmp.c_str(), img.width, img.height, Imf::WRITE_RGBA);
      file.setFrameBuffer(px.data(), 1, size_t(img.width));
      file.writePixels(img.height);
    } catch (const std::exception& e) {
      throw IoError("cannot write EXR '" + path + "': " + e.what());
    }
}
}  // namespace

void write_exr(const std::string& path, const Image& img) {
  write_atomically(path, [&](const std::string& tmp) { write_exr_file(tmp, path, img); });
}

Image read_exr(const std::string& path) {
  try {
    Imf::RgbaInputFile file(path.c_str());
    Imath::Box2i dw = file.dataWindow();
    int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    std::vector<Imf::Rgba> px(size_t(w) * h);
    file.setFrameBuffer(px.data() - dw.min.x - size_t(dw.min.y) * w, 1, size_t(w));
    file.readPixels(dw.min.y, dw.max.y);
    Image img(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Imf::Rgba& p = px[size_t(y) * w + x];
        float* d = img.at(x, h - 1 - y);
        d[0] = p.r, d[1] = p.g, d[2] = p.b, d[3] = p.a;
      }
    return img;
  } catch (const std::exception& e) {
    throw InputError("cannot read EXR '" + path + "': " + e.what());
  }
}

namespace {
// What write_image writes to `tmp` for `path` (by its extension).
std::function<void(const std::string&)> image_filler(const std::string& path, const Image& display, const Image& linear) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  auto ends = [&](const std::string& s) { return lower.size() >= s.size() && lower.compare(lower.size() - s.size(), s.size(), s) == 0; };
  if (ends(".png")) return [&path, &display](const std::string& tmp) { write_png_file(tmp, path, display); };
  if (ends(".exr")) return [&path, &linear](const std::string& tmp) { write_exr_file(tmp, path, linear); };
  throw InputError("--out " + path + ": unknown image type (allowed: .png, .exr)");
}
}  // namespace

void write_image(const std::string& path, const Image& display, const Image& linear) {
  write_atomically(path, image_filler(path, display, linear));
}

#ifdef CLOUDVIEWER_HAS_CLOUDGEN
struct ImageBatch::Impl {
  cloudgen::OutputBatch batch;
};
ImageBatch::ImageBatch() : impl_(std::make_unique<Impl>()) {}
ImageBatch::~ImageBatch() = default;
void ImageBatch::stage(const std::vector<ImageFile>& files) {
  for (const ImageFile& f : files) impl_->batch.stage(f.path, image_filler(f.path, *f.display, *f.linear));
}
void ImageBatch::commit() { impl_->batch.commit(); }
#else
struct ImageBatch::Impl {};  // without cloudgen's output batch: each image written when staged
ImageBatch::ImageBatch() = default;
ImageBatch::~ImageBatch() = default;
void ImageBatch::stage(const std::vector<ImageFile>& files) {
  for (const ImageFile& f : files) write_image(f.path, *f.display, *f.linear);
}
void ImageBatch::commit() {}
#endif

void write_images(const std::vector<ImageFile>& files) {
  ImageBatch batch;  // every file staged, then all published or none
  batch.stage(files);
  batch.commit();
}

ImageStats image_stats(const Image& img) {
  ImageStats s;
  double sum = 0, sum2 = 0;
  size_t n = 0;
  s.min = 1e300, s.max = -1e300;
  for (size_t i = 0; i < img.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    double v = img.rgba[i];
    if (!std::isfinite(v)) {
      ++s.nonfinite;
      continue;
    }
    s.min = std::min(s.min, v), s.max = std::max(s.max, v);
    sum += v, sum2 += v * v, ++n;
  }
  if (n) {
    s.mean = sum / n;
    s.stddev = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  } else {
    s.min = s.max = 0;
  }
  return s;
}

static void check_same(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("image sizes differ");
}

double rmse(const Image& a, const Image& b) {
  check_same(a, b);
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    double d = double(a.rgba[i]) - b.rgba[i];
    sum += d * d, ++n;
  }
  return n ? std::sqrt(sum / n) : 0;
}

double psnr(const Image& a, const Image& b, double peak) {
  double e = rmse(a, b);
  if (e == 0) return 999;
  return 20 * std::log10(peak / e);
}

double max_abs_diff(const Image& a, const Image& b) {
  check_same(a, b);
  double m = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i)
    if (i % 4 != 3) m = std::max(m, std::abs(double(a.rgba[i]) - b.rgba[i]));
  return m;
}

Image diff_image(const Image& a, const Image& b, double gain) {
  check_same(a, b);
  Image d(a.width, a.height);
  for (size_t i = 0; i < a.rgba.size(); ++i)
    d.rgba[i] = (i % 4 == 3) ? 1.f : float(std::abs(double(a.rgba[i]) - b.rgba[i]) * gain);
  return d;
}

}  // namespace cloudviewer
