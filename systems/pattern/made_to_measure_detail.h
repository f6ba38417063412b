// Shared by made_to_measure.cpp and made_to_measure_templates.cpp (not
// installed): the check of MadeToMeasureOptions both forms start with.
#pragma once

#include <atelier/engine/status.h>
#include <atelier/systems/pattern/made_to_measure.h>

namespace atelier::pattern_detail {

/// kInvalidArgument naming the first named line whose fraction is outside
/// [0, 1] or not finite.
[[nodiscard]] Status check_named_lines(const MadeToMeasureOptions& opt);

}  // namespace atelier::pattern_detail
