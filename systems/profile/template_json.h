// Readable profile-template files (issue #4): a versioned JSON document that
// stores everything a ProfileTemplate holds, so a template authored once can
// be inspected, edited by hand, and regenerated later. docs/template-format.md
// describes the format field by field.
//
// The model is stored as it is after compact() (a template with tombstones is
// written from a compacted copy, with its encodings and profiles remapped):
// nodes in index order, edges as (tail, head) node pairs in index order
// (halfedge 2e runs tail -> head), faces per surface as node cycles starting
// at the face's first halfedge, mesh edges as node chains, mesh loops,
// joints, attribute nodes and edges. Reading rebuilds the tables with the
// model primitives in that order, so every node, edge, halfedge and face gets
// its old index back and diff_tables(compact(original), read) is empty; the
// encodings and profiles therefore refer to the same elements.
//
// Doubles are written in the shortest form that reads back to the same bits
// (at most 17 significant digits), so a round trip is bit-exact.
//
// Reading never trusts the file: every index is range-checked and every
// structural rule (edges exist, faces on faceless halfedges, chains connected,
// joint members of equal length, one profile per edge) is checked before the
// primitive that relies on it runs; then validate_template() checks the whole.
// Any failure is an Error(kParse) naming the file, the JSON location (a JSON
// pointer such as "/surfaces/1/faces/3") and the problem.
//
// Reads/writes: a ProfileTemplate and one file (written atomically).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <atelier/systems/profile/profile_template.h>

namespace atelier {

/// The format tag and version written and accepted.
inline constexpr std::string_view kTemplateFormat = "atelier-template";
inline constexpr int kTemplateFormatVersion = 1;

/// Writes `t` atomically (nothing is left at `path` but what was there before
/// if anything fails). Throws Error naming the file: kIo for file-system
/// failures, kInvalidArgument for a template that cannot be written (it does
/// not validate, or holds non-finite numbers).
void write_template_json(const ProfileTemplate& t, const std::filesystem::path& path);

/// Largest magnitude of any number in a template file (lengths in metres,
/// parameters, weights): larger values are refused when reading.
inline constexpr double kTemplateMaxMagnitude = 1e4;

/// Reads and validates a template. Throws Error(kParse) naming the file, the
/// JSON location and the problem (kIo when the file cannot be read). Numbers
/// beyond kTemplateMaxMagnitude and `levels` above kMaxTemplateLevels are
/// refused. A UTF-8 byte-order mark is skipped.
[[nodiscard]] ProfileTemplate read_template_json(const std::filesystem::path& path);
/// The same, then check_template_references against the body the template
/// will be regenerated on: a feature point or body element out of range is
/// an Error(kParse) naming the file, the template and the node.
[[nodiscard]] ProfileTemplate read_template_json(const std::filesystem::path& path, const ReferenceBody& reference);

/// In-memory forms of the two above (same document, same checks).
[[nodiscard]] std::string template_to_json_string(const ProfileTemplate& t);
[[nodiscard]] ProfileTemplate template_from_json_string(std::string_view text, std::string_view source_name);

}  // namespace atelier
