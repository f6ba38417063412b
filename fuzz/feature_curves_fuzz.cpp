// libFuzzer harness: the feature-curve reader (JSON of named polylines,
// io/feature_curves.h parse_feature_curves, issue 26). The parser returns
// Expected and never throws: any exception is a bug.
#include <atelier/io/feature_curves.h>

#include <algorithm>
#include <cmath>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto r = atelier::parse_feature_curves(atelier::fuzz::text(data, size), "fuzz.json");
  if (!r) {
    // Every error names the file.
    if (r.status().message().rfind("fuzz.json", 0) != 0) std::abort();
    return 0;
  }
  // What the reader promises: known, distinct names; enough finite points
  // of magnitude at most 1e6, one line per point; units and up from the lists.
  const atelier::FeatureCurveFile& f = *r;
  if (f.curves.empty()) std::abort();
  if (f.scale != 1.0 && f.scale != 0.01 && f.scale != 0.001) std::abort();
  const auto names = atelier::feature_curve_names();
  for (std::size_t c = 0; c < f.curves.size(); ++c) {
    const auto& k = f.curves[c];
    if (std::find(names.begin(), names.end(), k.name) == names.end()) std::abort();
    for (std::size_t d = 0; d < c; ++d)
      if (f.curves[d].name == k.name) std::abort();
    if (k.points.size() < (k.closed ? 3u : 2u) || k.point_lines.size() != k.points.size()) std::abort();
    for (const auto& p : k.points)
      if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e6) std::abort();
  }
  return 0;
}
