#include <atelier/engine/status.h>

namespace atelier {

const char* to_string(ErrorCode c) noexcept {
  switch (c) {
    case ErrorCode::kOk: return "ok";
    case ErrorCode::kInvalidArgument: return "invalid argument";
    case ErrorCode::kStaleHandle: return "stale handle";
    case ErrorCode::kTopology: return "topology";
    case ErrorCode::kNonManifold: return "non-manifold";
    case ErrorCode::kJointRefused: return "refused on joint";
    case ErrorCode::kDegenerate: return "degenerate";
    case ErrorCode::kParse: return "parse error";
    case ErrorCode::kIo: return "i/o error";
    case ErrorCode::kMismatch: return "mismatch";
    case ErrorCode::kCancelled: return "cancelled";
    case ErrorCode::kUnsupported: return "unsupported";
    case ErrorCode::kInternal: return "internal error";
  }
  return "unknown";
}

std::string Status::to_string() const {
  if (is_ok()) return "ok";
  return std::string(atelier::to_string(code_)) + ": " + message_;
}

}  // namespace atelier
