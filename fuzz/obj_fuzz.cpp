// libFuzzer harness: the OBJ reader (io/obj.h).
#include <atelier/io/obj.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const atelier::Model m = atelier::read_obj_from_string(atelier::fuzz::text(data, size), "fuzz.obj");
    atelier::fuzz::require_valid(m);
  });
}
