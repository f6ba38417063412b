// Where the tests find ../shared/data (real data nobody here wrote; tests
// skip cleanly when it is absent).
#pragma once

#include <filesystem>

namespace atelier::testing {

/// ../shared/data/makehuman: MakeHuman's base body, targets and garments.
inline std::filesystem::path makehuman_dir() {
  return std::filesystem::path(ATELIER_SHARED_DATA) / "makehuman";
}

}  // namespace atelier::testing
