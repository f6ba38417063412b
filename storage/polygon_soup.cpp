#include <atelier/storage/polygon_soup.h>

#include <algorithm>
#include <string>

namespace atelier {

void PolygonSoup::add_face(std::span<const std::uint32_t> nodes) {
  face_nodes.insert(face_nodes.end(), nodes.begin(), nodes.end());
  face_offsets.push_back(static_cast<std::uint32_t>(face_nodes.size()));
}

std::vector<std::array<std::uint32_t, 2>> PolygonSoup::edges() const {
  std::vector<std::array<std::uint32_t, 2>> e;
  e.reserve(face_nodes.size());
  for (std::size_t f = 0; f + 1 < face_offsets.size(); ++f) {
    const std::uint32_t a = face_offsets[f], n = face_offsets[f + 1] - a;
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t u = face_nodes[a + k], v = face_nodes[a + (k + 1) % n];
      if (u != v) e.push_back({std::min(u, v), std::max(u, v)});
    }
  }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return e;
}

Status PolygonSoup::check(std::size_t vertex_count) const {
  if (vertex_count == 0) vertex_count = positions.size();
  if (face_offsets.empty() || face_offsets.front() != 0)
    return {ErrorCode::kInvalidArgument, "polygon soup: face offsets must start at 0"};
  if (face_offsets.back() != face_nodes.size())
    return {ErrorCode::kInvalidArgument, "polygon soup: face offsets end at " + std::to_string(face_offsets.back()) +
                                             " but there are " + std::to_string(face_nodes.size()) + " face nodes"};
  if (!corner_uv.empty() && corner_uv.size() != face_nodes.size())
    return {ErrorCode::kInvalidArgument, "polygon soup: " + std::to_string(corner_uv.size()) +
                                             " corner texture coordinates for " + std::to_string(face_nodes.size()) +
                                             " face corners"};
  for (std::size_t f = 0; f + 1 < face_offsets.size(); ++f) {
    if (face_offsets[f + 1] < face_offsets[f] + 3)
      return {ErrorCode::kInvalidArgument, "polygon soup: face " + std::to_string(f) + " has fewer than 3 corners"};
    for (std::uint32_t k = face_offsets[f]; k < face_offsets[f + 1]; ++k)
      if (face_nodes[k] >= vertex_count)
        return {ErrorCode::kInvalidArgument, "polygon soup: face " + std::to_string(f) + " uses vertex " +
                                                 std::to_string(face_nodes[k]) + " of " + std::to_string(vertex_count)};
  }
  return {};
}

}  // namespace atelier
