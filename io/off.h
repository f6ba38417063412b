// OFF (Object File Format) reader and writer.
//
// Reading: header OFF, COFF, NOFF, CNOFF or STOFF (counts may follow on the
// same line), then `nv nf ne`, nv vertex lines (x y z first; normals, colours
// and texture values after them are skipped), nf face lines `k i0 .. ik-1`
// (a colour may follow). `#` comments and blank lines are ignored. One
// surface named after the file stem ("off" for in-memory input). Errors are
// Error(kParse) naming the file, the line and the problem.
//
// Writing: all live nodes and faces of all surfaces, flattened, shortest exact
// decimal coordinates, through an AtomicFile. OFF has no way to keep
// surfaces apart: a model of several surfaces is merged into one (and its
// shared OBJ vertices stay separate nodes); write_off reports how many
// surfaces it merged so the caller can warn (the CLI's `convert` does).
// A file with no vertex is refused when reading.
#pragma once

#include <filesystem>
#include <string_view>

#include <atelier/storage/model.h>

namespace atelier {

[[nodiscard]] Model read_off(const std::filesystem::path& path);
[[nodiscard]] Model read_off_from_string(std::string_view text, std::string_view display_name = "<memory>");

/// Returns the number of live surfaces merged into the file's one mesh.
std::size_t write_off(const Model& m, const std::filesystem::path& path);

}  // namespace atelier
