// libFuzzer harness: the MakeHuman JSON readers, modifiers
// (measurement_modifiers.json, parse_measure_modifiers) and measurement loops
// (measures.json, parse_measures); the first byte picks the reader.
#include <atelier/io/makehuman/makehuman.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view rest = atelier::fuzz::text(data + 1, size - 1);
  return atelier::fuzz::run([&] {
    if (data[0] & 1) {
      (void)atelier::makehuman::parse_measure_modifiers(rest, "fuzz_modifiers.json");
    } else {
      const auto m = atelier::makehuman::parse_measures(rest, "fuzz_measures.json", 20000);
      for (const auto& [name, v] : m)
        for (std::uint32_t i : v)
          if (i >= 20000) std::abort();
    }
  });
}
