// Small checks shared by the test suites.
#pragma once

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/validate.h>
#include <gtest/gtest.h>

#include <utility>

namespace atelier::testing {

/// The value of an Expected, or a thrown Error (which fails the test) naming
/// its status: for set-up steps that must succeed.
template <class T>
T ok(Expected<T> e) {
  if (!e) throw Error(e.status());
  return std::move(e).value();
}

/// validate(m) passes (the standard's check after every operator).
inline void expect_valid(const Model& m) {
  const Status s = validate(m);
  ASSERT_TRUE(s) << s.to_string();
}

}  // namespace atelier::testing
