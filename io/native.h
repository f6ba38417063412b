// Native lossless model format (.atm).
//
// Little-endian binary: an 8-byte magic "ATELIER\x1a", a u32 version and a
// u32 section count, then fixed-order sections, each `u32 tag, u64 size,
// u32 CRC-32 of the payload, payload`. Sections: HEAD (complex-hole count and
// table sizes), NODE, EDGE (with the halfedge columns), FACE, SURF (names and
// flags), MEDG (mesh edges), LOOP, JOIN (joints with direction flags), ATND
// (attribute nodes), ATED (attribute edges with feature ids), PROP (property
// columns of the common scalar and vector types; columns of other types are
// not written).
//
// The model is written as it is after compact() (a model with tombstones is
// compacted on a copy first), so reading gives back tables equal to
// compact(original) slot for slot (diff_tables == ""). Reading checks sizes,
// checksums and every stored index before building anything, then runs
// validate(); any failure is an Error(kParse) naming the file, the section
// and the byte offset.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <atelier/storage/model.h>

namespace atelier {

void write_model(const Model& m, const std::filesystem::path& path);
[[nodiscard]] Model read_model(const std::filesystem::path& path);

/// The bytes write_model writes, and their reader (for in-memory use).
[[nodiscard]] std::string serialize_model(const Model& m);
[[nodiscard]] Model deserialize_model(std::string_view bytes, std::string_view display_name = "<memory>");

}  // namespace atelier
