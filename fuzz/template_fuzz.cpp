// libFuzzer harness: the profile-template JSON reader
// (systems/profile/template_json.h template_from_json_string). An accepted
// template must validate, write back to JSON and read again.
#include <atelier/systems/profile/template_json.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  atelier::ProfileTemplate t;
  try {
    t = atelier::template_from_json_string(atelier::fuzz::text(data, size), "fuzz.json");
  } catch (const atelier::Error&) {
    return 0;  // refused with a message
  }
  if (atelier::Status s = atelier::validate_template(t); !s) std::abort();
  try {
    (void)atelier::template_from_json_string(atelier::template_to_json_string(t), "fuzz-roundtrip.json");
  } catch (const atelier::Error& e) {
    std::fprintf(stderr, "accepted template does not round trip: %s\n", e.what());
    std::abort();
  }
  return 0;
}
