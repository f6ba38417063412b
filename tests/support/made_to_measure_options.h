// Made-to-measure options of the pattern tests: a pattern set without
// files, shared by made_to_measure_test.cpp and
// made_to_measure_templates_test.cpp.
#pragma once

#include <atelier/systems/pattern/made_to_measure.h>

namespace atelier::testing {

/// The options of a pattern set without files (no SVG, DXF or CSV).
inline MadeToMeasureOptions pattern_set_only(bool warm_start) {
  MadeToMeasureOptions o;
  o.files.svg = o.files.dxf = o.csv = false;
  o.warm_start = warm_start;
  return o;
}

}  // namespace atelier::testing
