// Wavefront OBJ reader and writer.
//
// Reading: `v` (x y z, extra values ignored), `vt` (per face corner, seams
// kept: the halfedge properties "corner_uv" and "source_texcoord", see
// storage/model.h HalfedgeTable; nodes.uv also gets the first corner's uv), `f`
// with v, v/vt, v/vt/vn, v//vn and negative (relative) indices; n-gons stay
// n-gons. `g NAME` and `o NAME` start a surface named NAME (faces before any
// of them go to "default"; a repeated name continues its surface). A vertex
// used by faces of several surfaces becomes one node per surface (a node
// belongs to one surface); the node property "source_vertex" (int32) keeps
// its 0-based OBJ index so write_obj writes it once again. Vertices used by no
// face become isolated nodes of "default". Comments, blank lines, \r\n, tabs,
// and `\` continuation lines are handled, a UTF-8 byte-order mark is
// skipped; other statements are skipped.
// Non-manifold edges: where three or more faces of different groups share an
// edge, their surfaces are joined there by a MESHJOINT (one single-edge
// MESHEDGE per surface, members clockwise about the direction from the lower
// to the higher OBJ vertex index). Within one group an edge of three or more
// faces is refused, naming the lines of those faces (a surface is a
// 2-manifold; put the extra faces in their own group to get a joint).
// Malformed input (a number out of a double's range included) throws
// Error(kParse) naming file, line and problem; a file with no `v` statement is
// refused the same way (text is not an empty mesh); file system failures
// throw Error(kIo).
//
// Writing: one `g` per live surface, every live face, coordinates in the
// shortest form that parses back to the same double (exact text round trip),
// through an AtomicFile (all or nothing). Texture coordinates: per corner
// when the model has "corner_uv" (one `vt` per distinct source index and
// value, in source order, so a file read and written keeps its `vt` list and
// seams), else per node from nodes.uv when any is non-zero.
//
// Polylines (`l` statements, curve networks of seed 003) are read and
// written by their own pair of functions below; read_obj skips them.
#pragma once

#include <filesystem>
#include <string_view>

#include <atelier/io/curve_network.h>
#include <atelier/storage/model.h>

namespace atelier {

[[nodiscard]] Model read_obj(const std::filesystem::path& path);
/// Parses OBJ text; `display_name` names the input in error messages.
[[nodiscard]] Model read_obj_from_string(std::string_view text, std::string_view display_name = "<memory>");

void write_obj(const Model& m, const std::filesystem::path& path);

/// The `l` statements of an OBJ file as polylines, in file order (ids 0, 1,
/// ... by order, lines = the statement's line). Indices as for faces (v or
/// v/vt, negative = relative); `v` lines are read as for read_obj, faces
/// and every other statement are ignored. Errors (Error(kParse) naming file
/// and line): an `l` with fewer than 2 indices, a bad or out-of-range index,
/// no `l` statement at all.
[[nodiscard]] PolylineSet read_obj_polylines(const std::filesystem::path& path);
[[nodiscard]] PolylineSet read_obj_polylines_from_string(std::string_view text,
                                                         std::string_view display_name = "<memory>");
/// Writes every curve as its own `v` lines and one `l` statement (atomic).
/// Throws Error(kInvalidArgument) for a non-finite point or a curve with
/// fewer than 2 points.
void write_obj_polylines(const PolylineSet& curves, const std::filesystem::path& path);

}  // namespace atelier
