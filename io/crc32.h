// CRC-32 (IEEE 802.3 / ISO 3309, reflected, polynomial 0xEDB88320): the
// checksum of PNG chunks and of the native format's sections.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace atelier::io_detail {

inline constexpr std::array<std::uint32_t, 256> kCrc32Table = [] {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}();

/// Continues a CRC over n bytes; start with 0xFFFFFFFF and complement the
/// result (crc32() does both).
[[nodiscard]] inline std::uint32_t crc32_update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) crc = kCrc32Table[(crc ^ p[i]) & 0xffu] ^ (crc >> 8);
  return crc;
}

[[nodiscard]] inline std::uint32_t crc32(const void* data, std::size_t n) noexcept {
  return crc32_update(0xFFFFFFFFu, static_cast<const std::uint8_t*>(data), n) ^ 0xFFFFFFFFu;
}

}  // namespace atelier::io_detail
