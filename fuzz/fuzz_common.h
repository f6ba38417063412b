// Shared by the libFuzzer harnesses: a parser may refuse its input with
// atelier::Error (that is the contract); any other exception, a crash, a
// leak, a hang or undefined behaviour is a bug that the fuzzer reports. A
// model a parser accepts must validate.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include <atelier/engine/status.h>
#include <atelier/storage/validate.h>

namespace atelier::fuzz {

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// A parser's result that does not validate is a bug: abort so that the
/// fuzzer keeps the input.
inline void require_valid(const Model& m) {
  if (Status s = validate(m); !s) {
    std::fprintf(stderr, "accepted model does not validate: %s\n", s.message().c_str());
    std::abort();
  }
}

template <class F>
int run(F&& parse) {
  try {
    parse();
  } catch (const Error&) {
    // Refused with a message: fine.
  }
  return 0;
}

}  // namespace atelier::fuzz
