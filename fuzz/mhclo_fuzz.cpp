// libFuzzer harness: the MakeHuman garment binding reader (.mhclo,
// io/makehuman/mhclo.h parse_mhclo), against a 20,000-vertex base mesh.
#include <atelier/io/makehuman/mhclo.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const auto b = atelier::makehuman::parse_mhclo(atelier::fuzz::text(data, size), "fuzz.mhclo", 20000);
    for (const auto& r : b.refs)
      for (std::uint32_t v : r.v)
        if (v >= 20000) std::abort();
  });
}
