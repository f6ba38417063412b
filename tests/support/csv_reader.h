// An RFC 4180 reader for tests (the reports' bodies.csv, issue 26): written
// apart from the writer (apps/atelier/html_report.cpp) so that a round trip
// checks the writer against the standard, not against itself.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace atelier::testing {

// RFC 4180 reader (test side): records of fields; quoted fields may hold
// commas, CRLF and doubled quotes. Every record must end with CRLF.
inline std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> out;
  std::vector<std::string> rec;
  std::string field;
  std::size_t i = 0;
  bool quoted = false, was_quoted = false;
  while (i < text.size()) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        i += 2;
      } else if (c == '"') {
        quoted = false;
        ++i;
      } else {
        field += c;
        ++i;
      }
      continue;
    }
    if (c == '"' && field.empty() && !was_quoted) {
      quoted = was_quoted = true;
      ++i;
    } else if (c == ',') {
      rec.push_back(field);
      field.clear();
      was_quoted = false;
      ++i;
    } else if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') {
      rec.push_back(field);
      out.push_back(rec);
      rec.clear();
      field.clear();
      was_quoted = false;
      i += 2;
    } else {
      EXPECT_NE(c, '\n') << "bare LF at byte " << i;
      EXPECT_NE(c, '"') << "quote inside an unquoted field at byte " << i;
      field += c;
      ++i;
    }
  }
  EXPECT_FALSE(quoted) << "unterminated quoted field";
  EXPECT_TRUE(rec.empty() && field.empty()) << "last record without CRLF";
  return out;
}

}  // namespace atelier::testing
