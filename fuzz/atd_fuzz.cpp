// libFuzzer harness: the detail-template reader (.atd,
// systems/garment/detail_template.h read_detail_from_bytes).
#include <atelier/systems/garment/detail_template.h>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return atelier::fuzz::run([&] {
    const atelier::DetailEncoding e = atelier::read_detail_from_bytes(atelier::fuzz::text(data, size), "fuzz.atd");
    // What the reader promises: offsets cover the entries, polygons in range.
    if (e.row.empty() || e.row.back() != e.polygon.size()) std::abort();
    for (std::uint32_t p : e.polygon)
      if (p >= e.polygon_count) std::abort();
  });
}
