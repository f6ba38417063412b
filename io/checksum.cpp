#include <atelier/io/checksum.h>

#include <zlib.h>

namespace atelier {

std::uint32_t crc32(const void* data, std::size_t n) noexcept {
  return static_cast<std::uint32_t>(::crc32_z(0L, static_cast<const Bytef*>(data), n));
}

}  // namespace atelier
