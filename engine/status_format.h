// Status messages assembled from parts (names, indices, handles, numbers).
#pragma once

#include <sstream>

#include <atelier/engine/status.h>

namespace atelier {

/// A Status whose message is `parts` streamed in order.
template <class... A>
[[nodiscard]] Status status_of(ErrorCode code, const A&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return {code, s.str()};
}

}  // namespace atelier
