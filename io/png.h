// PNG for pictures (rendered bodies and garments) and the HTML report's
// checks, through libpng (Debian's libpng-dev), the library every PNG tool
// trusts, instead of a codec of our own.
//
// Writing: 8-bit RGB, non-interlaced, one IDAT; libpng tries every filter
// per row (the heuristic of the PNG specification, section 12.8), so output
// bytes depend only on the pixels and the libpng version. Files are written
// through an AtomicFile (all or nothing).
//
// Reading: anything libpng reads (any bit depth, palette, grey, alpha,
// interlacing), as RGB8 (alpha composed on black, grey replicated); chunk
// CRCs are checked by libpng. Damaged data throws Error(kParse) naming the
// input; unreadable files throw Error(kIo).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

/// Row-major 8-bit RGB pixels, top row first.
struct RgbImage {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> pixels;  // 3 * width * height

  RgbImage() = default;
  RgbImage(std::uint32_t w, std::uint32_t h, std::uint8_t fill = 0)
      : width(w), height(h), pixels(std::size_t{3} * w * h, fill) {}
  [[nodiscard]] std::uint8_t* at(std::uint32_t x, std::uint32_t y) noexcept {
    return pixels.data() + 3 * (std::size_t{y} * width + x);
  }
  [[nodiscard]] const std::uint8_t* at(std::uint32_t x, std::uint32_t y) const noexcept {
    return pixels.data() + 3 * (std::size_t{y} * width + x);
  }
  friend bool operator==(const RgbImage&, const RgbImage&) = default;
};

/// Encodes the image as PNG bytes. Throws Error(kInvalidArgument) for an
/// empty image or a pixel array of the wrong size. `level` is zlib's 0..9.
[[nodiscard]] std::string encode_png(const RgbImage& image, int level = 6);
/// encode_png + AtomicFile.
void write_png(const RgbImage& image, const std::filesystem::path& path, int level = 6);

/// Decodes PNG bytes; `display_name` names the input in error messages.
[[nodiscard]] RgbImage decode_png(std::string_view bytes, std::string_view display_name = "<memory>");
[[nodiscard]] RgbImage read_png(const std::filesystem::path& path);

}  // namespace atelier
