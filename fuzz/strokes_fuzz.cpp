// libFuzzer harness: the stroke-file reader (systems/view/strokes.h
// parse_strokes, branch `sketch`). Built only once systems/view/strokes.cpp
// is on the branch being built (fuzz/CMakeLists.txt). The parser returns
// Expected: any exception is a bug; an accepted file must write back to
// JSON that reads again to the same strokes.
#include <atelier/systems/view/strokes.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto r = atelier::parse_strokes(atelier::fuzz::text(data, size), "fuzz.strokes.json");
  if (!r) return 0;
  for (const atelier::Stroke& s : r->strokes)
    for (const auto& p : s.points)
      if (!p.allFinite()) std::abort();
  const auto text = atelier::strokes_to_json(*r);
  if (!text) std::abort();
  const auto again = atelier::parse_strokes(*text, "fuzz-roundtrip.strokes.json");
  if (!again || again->strokes.size() != r->strokes.size()) std::abort();
  for (std::size_t i = 0; i < r->strokes.size(); ++i)
    if (again->strokes[i].points != r->strokes[i].points) std::abort();
  return 0;
}
