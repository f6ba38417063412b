// The layout of docs/architecture.md, kept true: every #include of the
// library, the CLI and the binding is checked against the document's table
// of which folder may include which, third-party headers that dominate
// compile time stay in the sources the document names, private helpers
// (*_detail.h) are included only from their own folder, and a source file
// over about 600 lines says at its top why it is long.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const fs::path kRoot = ATELIER_SOURCE_DIR;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split_list(const std::string& cell) {
  std::vector<std::string> out;
  std::stringstream ss(cell);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos) out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

/// Rows of the markdown table between `<!-- name: begin -->` and `end`:
/// first cell -> second cell.
std::map<std::string, std::string> table(const std::string& doc, const std::string& name) {
  const std::string begin = "<!-- " + name + ": begin -->", end = "<!-- " + name + ": end -->";
  const auto b = doc.find(begin), e = doc.find(end);
  std::map<std::string, std::string> rows;
  if (b == std::string::npos || e == std::string::npos) return rows;
  std::stringstream ss(doc.substr(b + begin.size(), e - b - begin.size()));
  std::string line;
  int n = 0;
  while (std::getline(ss, line)) {
    if (line.empty() || line[0] != '|') continue;
    if (n++ < 2) continue;  // header and separator
    std::vector<std::string> cells;
    std::string cell;
    std::stringstream ls(line.substr(1));
    while (std::getline(ls, cell, '|')) cells.push_back(cell);
    if (cells.size() < 2) continue;
    auto trim = [](std::string s) {
      const auto b2 = s.find_first_not_of(" \t"), e2 = s.find_last_not_of(" \t");
      return b2 == std::string::npos ? std::string() : s.substr(b2, e2 - b2 + 1);
    };
    rows[trim(cells[0])] = trim(cells[1]);
  }
  return rows;
}

/// The folder a path (relative to the root, '/'-separated) belongs to:
/// systems/<family>, io/<sub> or io, apps/<app>, or its first component.
std::string folder_of(const std::string& rel) {
  std::vector<std::string> parts;
  std::stringstream ss(rel);
  std::string p;
  while (std::getline(ss, p, '/')) parts.push_back(p);
  if (parts.size() >= 3 && (parts[0] == "systems" || parts[0] == "apps")) return parts[0] + "/" + parts[1];
  if (parts.size() >= 3 && parts[0] == "io") return "io/" + parts[1];
  return parts.empty() ? std::string() : parts[0];
}

struct Source {
  std::string rel;  // relative to the root
  std::string text;
};

std::vector<Source> sources() {
  std::vector<Source> out;
  for (const char* top : {"engine", "storage", "io", "systems", "apps", "python"}) {
    if (!fs::exists(kRoot / top)) continue;
    for (const auto& e : fs::recursive_directory_iterator(kRoot / top)) {
      const auto ext = e.path().extension();
      if (!e.is_regular_file() || (ext != ".h" && ext != ".cpp")) continue;
      out.push_back({fs::relative(e.path(), kRoot).generic_string(), slurp(e.path())});
    }
  }
  std::sort(out.begin(), out.end(), [](const Source& a, const Source& b) { return a.rel < b.rel; });
  return out;
}

const std::regex kInclude(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");

TEST(Architecture, TheDocumentHasItsTables) {
  const std::string doc = slurp(kRoot / "docs" / "architecture.md");
  const auto rules = table(doc, "include-rules");
  for (const char* f : {"engine", "storage", "io", "systems/mesh", "systems/spatial", "systems/smooth", "systems/view",
                        "systems/body", "systems/profile", "systems/garment", "apps/atelier"})
    EXPECT_TRUE(rules.count(f)) << "docs/architecture.md has no include rule for " << f;
  EXPECT_FALSE(table(doc, "third-party").empty());
  // Every folder of the library has a row (a new family must be placed in the picture).
  for (const Source& s : sources()) EXPECT_TRUE(rules.count(folder_of(s.rel))) << s.rel << ": its folder has no row";
}

TEST(Architecture, EveryIncludeIsAllowedByTheDocument) {
  const std::string doc = slurp(kRoot / "docs" / "architecture.md");
  const auto rules = table(doc, "include-rules");
  std::map<std::string, std::set<std::string>> allowed;
  for (const auto& [folder, list] : rules) {
    allowed[folder].insert(folder);
    for (const auto& f : split_list(list)) allowed[folder].insert(f);
  }
  std::size_t checked = 0;
  for (const Source& s : sources()) {
    const std::string from = folder_of(s.rel);
    const fs::path dir = (kRoot / s.rel).parent_path();
    std::stringstream ss(s.text);
    std::string line;
    int n = 0;
    while (std::getline(ss, line)) {
      ++n;
      std::smatch m;
      if (!std::regex_search(line, m, kInclude)) continue;
      const std::string what = m[2];
      const std::string where = s.rel + ":" + std::to_string(n) + ": #include " + m[1].str() + what;
      if (m[1] == "\"") {
        // Quotes: a file of the same folder only (private helpers, the CLI's own headers).
        EXPECT_TRUE(fs::exists(dir / what) && what.find('/') == std::string::npos)
            << where << ": library headers are included as <atelier/...>, quotes only for the same folder";
        ++checked;
        continue;
      }
      if (what.rfind("atelier/", 0) != 0) continue;
      const std::string target = what.substr(8);
      EXPECT_TRUE(fs::exists(kRoot / target)) << where << ": no such header";
      EXPECT_EQ(target.find("_detail.h"), std::string::npos)
          << where << ": a *_detail.h header is private: include it by its relative path from its own folder";
      const std::string to = folder_of(target);
      EXPECT_TRUE(allowed.count(from) && allowed[from].count(to))
          << where << ": docs/architecture.md does not let " << from << " include " << to;
      ++checked;
    }
  }
  EXPECT_GT(checked, 300u);
}

TEST(Architecture, HeavyThirdPartyHeadersStayInTheNamedSources) {
  const auto rows = table(slurp(kRoot / "docs" / "architecture.md"), "third-party");
  ASSERT_FALSE(rows.empty());
  for (const Source& s : sources()) {
    std::stringstream ss(s.text);
    std::string line;
    while (std::getline(ss, line)) {
      std::smatch m;
      if (!std::regex_search(line, m, kInclude) || m[1] != "<") continue;
      for (const auto& [prefix, files] : rows) {
        if (m[2].str().rfind(prefix, 0) != 0) continue;
        const auto list = split_list(files);
        EXPECT_TRUE(std::find(list.begin(), list.end(), s.rel) != list.end())
            << s.rel << " includes <" << m[2] << ">: docs/architecture.md keeps " << prefix << " in " << files;
      }
    }
  }
}

TEST(Architecture, LongSourcesSayWhyAtTheirTop) {
  // "No source file over about 600 lines without a reason at its top": a
  // file over 650 lines carries a "Why this file is long:" note in its
  // first 40 lines.
  for (const Source& s : sources()) {
    const auto lines = std::count(s.text.begin(), s.text.end(), '\n');
    if (lines <= 650) continue;
    std::stringstream ss(s.text);
    std::string line, head;
    for (int i = 0; i < 40 && std::getline(ss, line); ++i) head += line + "\n";
    EXPECT_NE(head.find("Why this file is long:"), std::string::npos)
        << s.rel << " has " << lines << " lines and no \"Why this file is long:\" note at its top";
  }
}

}  // namespace
