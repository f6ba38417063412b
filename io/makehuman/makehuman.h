// MakeHuman data: base mesh, morph targets and measurement loops
// (../shared/data/makehuman, described in its README).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
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
/// (kParse) naming the file and line for a bad line, a number out of float
/// range, an index >= vertex_count, or a file with no displacement at all.
[[nodiscard]] Target read_target(const std::filesystem::path& file, std::uint32_t vertex_count);
/// The same on text already read; `file` names it in errors and gives the name.
[[nodiscard]] Target parse_target(std::string_view text, const std::filesystem::path& file, std::uint32_t vertex_count);

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

/// Reads base.obj (v, vt and f lines, g groups; the rest skipped): each
/// group's corner_uv holds the texture coordinate of every face corner when
/// every corner of the file has one (else all are empty). Throws
/// atelier::Error naming file and line on malformed input (numbers out of
/// float range included) and for a file with no vertex or no face. A UTF-8
/// byte-order mark is skipped.
[[nodiscard]] BaseMesh read_base_mesh(const std::filesystem::path& file);
[[nodiscard]] BaseMesh parse_base_mesh(std::string_view text, const std::filesystem::path& file);

/// Measurement loops and landmark chains from measures.json (vertex indices).
[[nodiscard]] std::map<std::string, std::vector<std::uint32_t>> read_measures(const std::filesystem::path& file,
                                                                              std::uint32_t vertex_count);
[[nodiscard]] std::map<std::string, std::vector<std::uint32_t>> parse_measures(std::string_view text,
                                                                               const std::filesystem::path& file,
                                                                               std::uint32_t vertex_count);

/// One two-sided measure slider of modifiers/measurement_modifiers.json: the
/// target stem and the suffixes of its two sides ("<target>-decr.target",
/// "<target>-incr.target" unless the file names others).
struct MeasureModifier {
  std::string target;
  std::string min = "decr";
  std::string max = "incr";
};
/// Reads the modifier groups (`[{"group": ..., "modifiers": [{"target": ...,
/// "min": ..., "max": ...}]}]`); entries without a target are skipped. Throws
/// atelier::Error (kParse) naming the file and the JSON location for any
/// other shape.
[[nodiscard]] std::vector<MeasureModifier> read_measure_modifiers(const std::filesystem::path& file);
[[nodiscard]] std::vector<MeasureModifier> parse_measure_modifiers(std::string_view text,
                                                                   const std::filesystem::path& file);

}  // namespace atelier::makehuman
