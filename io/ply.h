// Stanford PLY reader and writer.
//
// Reading: ascii, binary_little_endian and binary_big_endian. The `vertex`
// element needs x, y, z (any scalar type; float or double in practice); u/v,
// s/t or texture_u/texture_v go to nodes.uv; every other property, of every
// PLY scalar or list type, is skipped. Faces come from the `face` element's
// `vertex_indices` (or `vertex_index`) list, any count and index type; other
// elements are skipped. One surface named after the file stem ("ply" for
// in-memory input), or, when the `face` element has an integer `surface`
// property, one surface per distinct value (ascending; named by
// "comment surface <id> <name>" header lines, else "<stem>_<id>"; each gets
// the vertices its faces use, unused vertices go to the first). A file with
// no vertex is refused. Malformed input throws Error(kParse) naming the file,
// the line (ascii) or byte offset (binary), the element and the problem.
//
// Writing: all live nodes and faces, binary little-endian with double
// coordinates (bit exact), or ascii with the shortest exact decimal form.
// A model of several surfaces gets the `surface` face property and the
// naming comments, so it reads back as the same surfaces. Written through an
// AtomicFile.
#pragma once

#include <filesystem>
#include <string_view>

#include <atelier/storage/model.h>

namespace atelier {

[[nodiscard]] Model read_ply(const std::filesystem::path& path);
[[nodiscard]] Model read_ply_from_string(std::string_view bytes, std::string_view display_name = "<memory>");

void write_ply(const Model& m, const std::filesystem::path& path, bool binary = true);

}  // namespace atelier
