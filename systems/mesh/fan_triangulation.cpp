#include <atelier/systems/mesh/fan_triangulation.h>

#include <string>

namespace atelier {

Expected<SurfaceTriangles> fan_triangulate(const Model& model, std::span<const SurfaceIdx> surfaces) {
  std::vector<std::uint8_t> wanted(model.surfaces.slots.capacity(), surfaces.empty() ? 1 : 0);
  for (SurfaceIdx s : surfaces) {
    if (!model.alive(s)) {
      return Status(ErrorCode::kStaleHandle, "fan_triangulate: surface " + std::to_string(s.value) + " is not alive");
    }
    wanted[s.value] = 1;
  }
  SurfaceTriangles out;
  std::vector<NodeIdx> corners;
  const std::size_t nf = model.faces.slots.capacity();
  for (std::uint32_t f = 0; f < nf; ++f) {
    const FaceIdx fi{f};
    if (!model.alive(fi)) continue;
    const SurfaceIdx s = model.faces.surface[f];
    if (!s.valid() || s.value >= wanted.size() || !wanted[s.value]) continue;
    model.face_nodes(fi, corners);
    for (std::size_t j = 1; j + 1 < corners.size(); ++j) {
      out.triangles.push_back({corners[0].value, corners[j].value, corners[j + 1].value});
      out.face.push_back(fi);
    }
  }
  return out;
}

std::vector<Triangle> fan_triangulate(const PolygonSoup& soup) {
  std::vector<Triangle> tris;
  tris.reserve(soup.face_nodes.size());
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const auto face = soup.face(f);
    for (std::size_t c = 1; c + 1 < face.size(); ++c) tris.push_back({face[0], face[c], face[c + 1]});
  }
  return tris;
}

}  // namespace atelier
