// The checksum of Atelier's native formats (.atm sections, .atd files): the
// CRC-32 of zlib (IEEE 802.3 / ISO 3309), the one PNG and gzip use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace atelier {

/// CRC-32 of n bytes.
[[nodiscard]] std::uint32_t crc32(const void* data, std::size_t n) noexcept;
[[nodiscard]] inline std::uint32_t crc32(std::string_view bytes) noexcept { return crc32(bytes.data(), bytes.size()); }

}  // namespace atelier
