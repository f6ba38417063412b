// MakeHuman garment bindings (.mhclo), MakeHuman's own way of fitting a
// garment on any body (../shared/data/makehuman/clothes/README.md):
//   fitted = w0 H[i0] + w1 H[i1] + w2 H[i2] + (sx dx, sy dy, sz dz),
//   s_axis = |H[a].axis - H[b].axis| / d   from the x_scale/y_scale/z_scale lines.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/math.h>

namespace atelier::makehuman {

struct GarmentBinding {
  std::string name;
  std::string obj_file;
  int z_depth = 0;                                // layer order (inner first)
  bool has_z_depth = false;                       // the file has a z_depth line
  std::array<std::uint32_t, 3> scale_a{}, scale_b{};  // per axis: reference vertex pair
  std::array<double, 3> scale_d{1, 1, 1};         // per axis: reference distance
  std::array<bool, 3> has_scale{};
  struct Ref {
    std::array<std::uint32_t, 3> v{};
    std::array<double, 3> w{};
    Vec3d offset = Vec3d::Zero();
  };
  std::vector<Ref> refs;                 // one per garment vertex, in obj order
  std::vector<std::uint32_t> delete_verts;  // body vertices hidden under the garment
};

/// Reads a .mhclo file. Throws atelier::Error (kParse) naming file and line on
/// a malformed line, a number out of range, a vertex index >=
/// body_vertex_count, or a file with no `verts` section. Blank and
/// whitespace-only lines are skipped wherever they are, inside a `verts`
/// section too, as MakeHuman's own reader does (a line with no word is
/// ignored, it does not end the section); a UTF-8 byte-order mark is skipped.
[[nodiscard]] GarmentBinding read_mhclo(const std::filesystem::path& file, std::uint32_t body_vertex_count);
/// The same on text already read; `file` names it in errors.
[[nodiscard]] GarmentBinding parse_mhclo(std::string_view text, const std::filesystem::path& file,
                                         std::uint32_t body_vertex_count);

}  // namespace atelier::makehuman
