#include "boolean_detail.h"
namespace atelier::net_detail {
Status apply_paper_mode(PolygonSoup&, std::span<const std::array<std::uint32_t, 2>>, std::span<const std::uint8_t>,
                        std::span<const std::uint8_t>, int, std::size_t&, std::size_t&, std::size_t&, std::size_t&,
                        std::size_t&, double&) {
  return {ErrorCode::kUnsupported, "paper mode: work in progress"};
}
}  // namespace atelier::net_detail
