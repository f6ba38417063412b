// libFuzzer harness: the native model reader (.atm, io/native.h).
#include <atelier/io/native.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const atelier::Model m = atelier::deserialize_model(atelier::fuzz::text(data, size), "fuzz.atm");
    atelier::fuzz::require_valid(m);
  });
}
