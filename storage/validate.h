// validate(): checks every topological invariant of a Model. Tests run it
// after every operator and system.
//
// Reads: every table. Writes: nothing. (In storage/ because it checks the
// tables' own invariants and every layer above, I/O included, uses it.)
#pragma once

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

struct ValidateOptions {
  /// Joint nodes must coincide within this distance, relative to (1 + the
  /// model's bounding-box diagonal).
  double joint_tolerance = 1e-9;
  /// Check the Euler-Poincare formula (needs O(n) union-find passes).
  bool check_euler = true;
};

/// Returns ok, or the first violated invariant naming the element.
[[nodiscard]] Status validate(const Model& m, const ValidateOptions& opt = {});

}  // namespace atelier
