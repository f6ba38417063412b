// libFuzzer harness: the MakeHuman morph-target reader
// (io/makehuman/makehuman.h parse_target), against a 20,000-vertex base mesh.
#include <atelier/io/makehuman/makehuman.h>

#include <cmath>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const auto t = atelier::makehuman::parse_target(atelier::fuzz::text(data, size), "fuzz.target", 20000);
    for (std::size_t i = 0; i < t.index.size(); ++i)
      if (t.index[i] >= 20000 || !t.delta[i].allFinite()) std::abort();
  });
}
