// Bits of EdgeTable::flags (storage/model.h). Edge splits copy an edge's
// flags to both halves (systems/mesh subdivide_uniform, Euler splits,
// triangulation, sketch cuts), so a mark on a profile template's edge
// carries through regeneration to every refined edge along it, on every
// body.
#pragma once

#include <cstdint>

namespace atelier {

/// A seam: the pattern is cut along this edge (systems/pattern/seams.h,
/// SeamOptions::marked). Set by TemplateBuilder::seam on template edges.
inline constexpr std::uint8_t kEdgeSeam = 1u << 0;

}  // namespace atelier
