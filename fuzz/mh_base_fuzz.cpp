// libFuzzer harness: the MakeHuman base-mesh reader (base.obj and the
// garment meshes; io/makehuman/makehuman.h parse_base_mesh).
#include <atelier/io/makehuman/makehuman.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const auto m = atelier::makehuman::parse_base_mesh(atelier::fuzz::text(data, size), "fuzz.obj");
    for (const auto& g : m.groups)
      if (!g.check(m.positions.size())) std::abort();
  });
}
