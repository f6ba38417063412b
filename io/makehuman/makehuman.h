// MakeHuman data: base mesh, morph targets and measurement loops
// (../shared/data/makehuman, described in its README).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier::makehuman {

/// A morph target: sparse displacements of base-mesh vertices.
struct Target {
  std::string name;                  // file stem, e.g. "universal-female-young-averagemuscle-averageweight"
  std::vector<std::uint32_t> index;  // 0-based vertex indices, strictly as in the file
  std::vector<Vec3f> delta;          // displacement of each listed vertex (base-mesh units)
};

/// Reads `INDEX DX DY DZ` lines (after `#` comments). Throws atelier::Error
/// (kParse) naming the file and line for a bad line or an index >= vertex_count.
[[nodiscard]] Target read_target(const std::filesystem::path& file, std::uint32_t vertex_count);

/// The base mesh: every vertex of base.obj (targets index into all of them)
/// and the faces of each group, as polygons over the global vertex indices.
struct BaseMesh {
  std::vector<Vec3f> positions;
  struct Group : PolygonSoup {  // faces over the global vertex indices; positions unused
    std::string name;
  };
  std::vector<Group> groups;
  [[nodiscard]] const Group* group(std::string_view name) const noexcept;
};

/// Reads base.obj (v and f lines, g groups; vt and the rest skipped). Throws
/// atelier::Error naming file and line on malformed input.
[[nodiscard]] BaseMesh read_base_mesh(const std::filesystem::path& file);

/// Measurement loops and landmark chains from measures.json (vertex indices).
[[nodiscard]] std::map<std::string, std::vector<std::uint32_t>> read_measures(const std::filesystem::path& file,
                                                                              std::uint32_t vertex_count);

}  // namespace atelier::makehuman
