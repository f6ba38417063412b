// libFuzzer harness: the OFF reader (io/off.h).
#include <atelier/io/off.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const atelier::Model m = atelier::read_off_from_string(atelier::fuzz::text(data, size), "fuzz.off");
    atelier::fuzz::require_valid(m);
  });
}
