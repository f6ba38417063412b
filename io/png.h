// PNG output for pictures (issue #6: rendered bodies and garments), with a
// minimal reader used by the tests and by the HTML report's size checks.
//
// Writing: 8-bit RGB, non-interlaced, one IDAT compressed with zlib; each row
// gets the PNG filter (None, Sub, Up, Average, Paeth) with the smallest sum of
// absolute differences (the heuristic of the PNG specification, section
// 12.8), so output bytes depend only on the pixels. Files are written through
// an AtomicFile (all or nothing).
//
// Reading: 8-bit greyscale, grey+alpha, RGB or RGBA, non-interlaced (what
// write_png and most tools produce); every chunk CRC is checked, IDAT chunks
// are concatenated and inflated, all five filters are undone. The result is
// always RGB8 (alpha dropped, grey replicated). Anything else throws
// Error(kParse) naming the problem; unreadable files throw Error(kIo).
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

/// CRC-32 of the PNG specification (ISO 3309 polynomial), as stored in chunks.
[[nodiscard]] std::uint32_t png_crc32(std::span<const std::uint8_t> bytes) noexcept;

/// Encodes the image as PNG bytes. Throws Error(kInvalidArgument) for an
/// empty image or a pixel array of the wrong size. `level` is zlib's 0..9.
[[nodiscard]] std::string encode_png(const RgbImage& image, int level = 6);
/// encode_png + AtomicFile.
void write_png(const RgbImage& image, const std::filesystem::path& path, int level = 6);

/// Decodes PNG bytes; `display_name` names the input in error messages.
[[nodiscard]] RgbImage decode_png(std::string_view bytes, std::string_view display_name = "<memory>");
[[nodiscard]] RgbImage read_png(const std::filesystem::path& path);

}  // namespace atelier
