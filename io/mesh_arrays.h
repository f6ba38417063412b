// Helpers shared by the mesh readers and writers: whole-file reads, parse
// errors that name file and location, exact number formatting, one polygon
// soup per surface built through add_polygon_surface (storage/builder.h), and
// a flat view of a model for the single-surface formats (PLY, OFF).
#pragma once

#include <charconv>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

class AtomicFile;

namespace io_detail {

/// Whole file as bytes; throws Error(kIo) naming the path.
[[nodiscard]] std::string read_file_bytes(const std::filesystem::path& path);

/// Error(kParse) with "<file>: <where>: <what>".
[[nodiscard]] Error parse_error(std::string_view file, std::string_view where, std::string_view what);
[[nodiscard]] Error parse_error_at_line(std::string_view file, std::size_t line, std::string_view what);

/// Shortest decimal text that parses back to the same double (std::to_chars
/// round-trip guarantee, never longer than max_digits10 significant digits).
void append_double(std::string& out, double v);
void append_uint(std::string& out, std::uint64_t v);

/// Strict number parsing of a whole token (a leading '+' is accepted). A
/// number beyond the range of a double (1e400) is refused, not read as 0 or
/// inf; one below the smallest subnormal reads as the nearest (0 or a
/// subnormal), as strtod gives.
[[nodiscard]] std::optional<double> parse_double(std::string_view token) noexcept;
[[nodiscard]] std::optional<std::int64_t> parse_int(std::string_view token) noexcept;
/// Why parse_double/parse_int refused a token, for messages:
/// "number 'T' is out of range (beyond a double)" or "non-numeric token 'T'".
[[nodiscard]] std::string number_problem(std::string_view token, bool integer = false);

/// The text without a leading UTF-8 byte-order mark (EF BB BF), which some
/// editors write: it is not part of the first statement.
[[nodiscard]] std::string_view skip_utf8_bom(std::string_view text) noexcept;

/// Splits on blanks (space, tab, \r, \v, \f).
void split_blanks(std::string_view line, std::vector<std::string_view>& out);

/// One surface's polygon soup, as read from a file, with the location of
/// every face (a line number or a byte offset) for error messages.
struct SurfaceSoup : PolygonSoup {
  std::string name;
  std::vector<Vec2d> uv;                   // empty or one per position
  std::vector<std::int32_t> source;        // empty or one per position: index in the file's vertex list
  std::vector<std::uint64_t> face_where;   // one per face
  std::vector<std::int32_t> corner_texcoord;  // empty or one per face corner: the file's texcoord index, -1 none
};

/// Adds the soup as one surface. Builder errors become Error(kParse) naming
/// the file and, for each face the builder names, where it came from
/// (`where_label` is "line" or "byte offset"). Also fills nodes.uv, the
/// "source_vertex" node property, and the halfedge (face-corner) properties
/// "corner_uv" and "source_texcoord" when the soup has them.
void add_soup_surface(Model& m, SurfaceSoup& soup, std::string_view file, std::string_view where_label);

/// The live part of a model as one flat polygon list: live nodes numbered
/// densely in index order, live faces in index order (surface by surface is
/// not needed: PLY and OFF have a single mesh).
struct FlatMesh : PolygonSoup {  // positions unused; face nodes are dense indices
  std::vector<NodeIdx> nodes;               // dense -> model node
  std::vector<std::uint32_t> dense;         // model node -> dense (kInvalid for dead)
  std::vector<FaceIdx> faces;
};
[[nodiscard]] FlatMesh flatten(const Model& m);

/// Throws Error(kInvalidArgument) when a node about to be written has a
/// non-finite coordinate: the file would not read back.
void require_finite(const Vec3d& p, NodeIdx v, const std::filesystem::path& path);

}  // namespace io_detail
}  // namespace atelier
