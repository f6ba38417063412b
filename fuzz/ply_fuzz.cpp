// libFuzzer harness: the PLY reader (io/ply.h).
#include <atelier/io/ply.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const atelier::Model m = atelier::read_ply_from_string(atelier::fuzz::text(data, size), "fuzz.ply");
    atelier::fuzz::require_valid(m);
  });
}
