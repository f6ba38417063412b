// PNG through libpng (Debian's libpng-dev): the writer with libpng's
// adaptive filtering, the reader through its simplified API.
#include <atelier/io/png.h>

#include <png.h>

#include <csetjmp>
#include <cstring>
#include <string>
#include <vector>

#include <atelier/engine/status.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>

namespace atelier {

namespace {

Error png_error(std::string_view name, std::string_view what) {
  return Error(Status(ErrorCode::kParse, std::string(name) + ": " + std::string(what)));
}

void append_bytes(png_structp png, png_bytep data, png_size_t n) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), n);
}
void no_flush(png_structp) {}
// libpng reports errors by longjmp: the message is kept for the Error thrown
// after it.
void on_error(png_structp png, png_const_charp msg) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = msg ? msg : "libpng error";
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

}  // namespace

std::string encode_png(const RgbImage& image, int level) {
  if (image.width == 0 || image.height == 0)
    throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: empty image"));
  if (image.pixels.size() != std::size_t{3} * image.width * image.height)
    throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: pixel array of the wrong size"));
  if (level < 0 || level > 9) throw Error(Status(ErrorCode::kInvalidArgument, "encode_png: level outside 0..9"));
  std::string out, message;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &message, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw Error(Status(ErrorCode::kInternal, "encode_png: libpng could not start"));
  }
  // Nothing with a destructor is created between setjmp and the longjmp.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw Error(Status(ErrorCode::kInternal, "encode_png: " + message));
  }
  png_set_write_fn(png, &out, append_bytes, no_flush);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, level);
  // Every filter tried per row (libpng picks by the sum of absolute
  // differences, PNG specification section 12.8): bytes depend only on the
  // pixels and the libpng version.
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_ALL_FILTERS);
  // One IDAT for the whole image data (pictures are at most a few MB).
  png_set_compression_buffer_size(png, 1u << 20);
  png_write_info(png, info);
  for (std::uint32_t y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_bytep>(image.pixels.data() + std::size_t{3} * image.width * y));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return out;
}

void write_png(const RgbImage& image, const std::filesystem::path& path, int level) {
  const std::string bytes = encode_png(image, level);
  write_atomically(path, [&](AtomicFile& f) { f.write(bytes); });
}

namespace {

struct MemoryInput {
  std::string_view bytes;
  std::size_t pos = 0;
};
void read_bytes(png_structp png, png_bytep out, png_size_t n) {
  auto* in = static_cast<MemoryInput*>(png_get_io_ptr(png));
  if (n > in->bytes.size() - in->pos) png_error(png, "the file ends inside a chunk (truncated)");
  std::memcpy(out, in->bytes.data() + in->pos, n);
  in->pos += n;
}

}  // namespace

RgbImage decode_png(std::string_view bytes, std::string_view name) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kSignature, 8) != 0)
    throw png_error(name, "not a PNG file (bad signature)");
  std::string message;
  MemoryInput in{bytes, 0};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &message, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw Error(Status(ErrorCode::kInternal, "decode_png: libpng could not start"));
  }
  // The image and row pointers live outside the setjmp scope (a longjmp
  // skips destructors of objects made after it).
  RgbImage img;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw png_error(name, "damaged PNG near byte offset " + std::to_string(in.pos) + ": " + message);
  }
  png_set_read_fn(png, &in, read_bytes);
  png_set_user_limits(png, 1u << 24, 1u << 24);
  png_read_info(png, info);
  const std::uint32_t w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  if (std::size_t{w} * h > (std::size_t{1} << 28)) png_error(png, "image too large");
  // Whatever the file holds, RGB8: palettes and low bit depths expanded,
  // 16 bits reduced, grey replicated, alpha dropped.
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_gray_to_rgb(png);
  png_set_strip_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != std::size_t{3} * w) png_error(png, "unexpected row size after conversion");
  img = RgbImage(w, h);
  rows.resize(h);
  for (std::uint32_t y = 0; y < h; ++y) rows[y] = img.pixels.data() + std::size_t{3} * w * y;
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);  // the chunks after the image and IEND, with their CRCs
  png_destroy_read_struct(&png, &info, nullptr);
  if (in.pos != bytes.size())
    throw png_error(name, std::to_string(bytes.size() - in.pos) + " bytes after the IEND chunk");
  return img;
}

RgbImage read_png(const std::filesystem::path& path) {
  const std::string bytes = io_detail::read_file_bytes(path);
  return decode_png(bytes, path.string());
}

}  // namespace atelier
