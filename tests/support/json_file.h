// Reading a JSON file written by the CLI (reports, records) in tests.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace atelier::testing {

/// The parsed contents of `p` (throws nlohmann's parse_error, which fails
/// the test, when the file is missing or malformed).
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream f(p);
  return nlohmann::json::parse(f);
}

}  // namespace atelier::testing
