#include "cloudgen/png_read.h"

#include <png.h>

#include <csetjmp>
#include <cstring>
#include <memory>

#include "cloudgen/errors.h"

namespace cloudgen {
namespace {

struct PngRead {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngRead() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  }
};

struct Source {
  const uint8_t* data;
  size_t size, at;
};

// libpng reports errors through longjmp; the message is kept for the InputError thrown afterwards.
void on_error(png_structp png, png_const_charp msg) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  *text = msg ? msg : "unknown libpng error";
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

void on_read(png_structp png, png_bytep out, png_size_t n) {
  auto* s = static_cast<Source*>(png_get_io_ptr(png));
  if (n > s->size - s->at) png_error(png, "the file ends early (truncated PNG)");
  std::memcpy(out, s->data + s->at, n);
  s->at += n;
}

}  // namespace

bool is_png(const uint8_t* data, size_t size) { return size >= 8 && png_sig_cmp(data, 0, 8) == 0; }

PngPixels decode_png(const uint8_t* data, size_t size, const std::string& what,
                     const std::function<void(const PngHeader&)>& check, const std::string& suffix) {
  // Everything with a destructor lives on the heap or before setjmp: libpng's longjmp leaves
  // automatic objects changed after setjmp indeterminate.
  PngRead r;
  auto message = std::make_unique<std::string>();
  auto src = std::make_unique<Source>(Source{data, size, 0});
  auto out = std::make_unique<PngPixels>();
  std::vector<png_bytep> rows;
  r.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message.get(), on_error, on_warning);
  if (!r.png) throw InputError(what + ": libpng could not start");
  r.info = png_create_info_struct(r.png);
  if (!r.info) throw InputError(what + ": libpng could not start");
  if (setjmp(png_jmpbuf(r.png))) throw InputError(what + ": " + *message + suffix);
  png_set_read_fn(r.png, src.get(), on_read);
  png_read_info(r.png, r.info);
  PngHeader h;
  h.width = png_get_image_width(r.png, r.info);
  h.height = png_get_image_height(r.png, r.info);
  h.depth = png_get_bit_depth(r.png, r.info);
  const int color = png_get_color_type(r.png, r.info);
  h.colour = (color & PNG_COLOR_MASK_COLOR) != 0;
  h.palette = color == PNG_COLOR_TYPE_PALETTE;
  check(h);  // may throw: nothing allocated for the rows yet
  if (h.palette) png_set_palette_to_rgb(r.png);
  if (!h.colour && h.depth < 8) png_set_expand_gray_1_2_4_to_8(r.png);
  png_read_update_info(r.png, r.info);
  out->width = h.width, out->height = h.height;
  out->channels = png_get_channels(r.png, r.info);
  out->depth = png_get_bit_depth(r.png, r.info);
  out->row_bytes = png_get_rowbytes(r.png, r.info);
  out->bytes.resize(out->row_bytes * h.height);
  rows.resize(h.height);
  for (png_uint_32 j = 0; j < h.height; ++j) rows[j] = out->bytes.data() + out->row_bytes * j;
  png_read_image(r.png, rows.data());
  png_read_end(r.png, nullptr);
  return std::move(*out);
}

}  // namespace cloudgen
