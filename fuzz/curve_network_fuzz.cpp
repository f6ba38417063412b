// libFuzzer harness: the curve-network reader (`CURVE i` format,
// io/curve_network.h parse_curve_network, branch `curvenet`). Built only
// once io/curve_network.h is on the branch being built (fuzz/CMakeLists.txt).
// The parser returns Expected and never throws: any exception is a bug.
#include <atelier/io/curve_network.h>

#include <cmath>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto r = atelier::parse_curve_network(atelier::fuzz::text(data, size), "fuzz.curve");
  if (!r) return 0;
  // What the reader promises: CSR offsets over the points, one id per
  // curve, at least 2 finite points per curve.
  const atelier::PolylineSet& s = *r;
  if (s.offsets.empty() || s.offsets.front() != 0 || s.offsets.back() != s.points.size()) std::abort();
  if (s.ids.size() != s.size()) std::abort();
  for (std::size_t c = 0; c < s.size(); ++c) {
    if (s.offsets[c + 1] < s.offsets[c] + 2) std::abort();
    for (const auto& p : s.curve(c))
      if (!p.allFinite()) std::abort();
  }
  return 0;
}
