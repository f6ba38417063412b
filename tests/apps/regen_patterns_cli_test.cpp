// `atelier regen --patterns` (issue 22): a made-to-measure pattern set per
// body and template (SVG per piece, DXF, measurements CSV) beside the body's
// record, figures in the record; a rerun skips bodies whose sets are done,
// and a rerun with --patterns after a run without them makes the sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::template_args;

using CliRun = atelier::testing::CommandResult;

using atelier::testing::run_cli;

std::vector<fs::path> records(const fs::path& out) {
  std::vector<fs::path> r;
  for (const auto& e : fs::directory_iterator(out / "bodies"))
    if (e.path().extension() == ".json") r.push_back(e.path());
  std::sort(r.begin(), r.end());
  return r;
}

}  // namespace

TEST(RegenPatternsCli, EveryBodyGetsAPatternSetPerTemplateAndARerunSkipsThem) {
  const fs::path out = atelier::testing::scratch_dir("regen_patterns");
  const CliRun r = run_cli("--threads 2 regen" + template_args() + " --count 1 --patterns --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::map<std::string, std::size_t> pieces = {{"top", 5}, {"skirt", 1}, {"trousers", 3}};
  const auto recs = records(out);
  ASSERT_EQ(recs.size(), 1u);
  std::map<fs::path, fs::file_time_type> written;
  for (const fs::path& rec : recs) {
    const auto j = nlohmann::json::parse(read_bytes(rec));
    ASSERT_TRUE(j.value("ok", false)) << j.dump();
    const fs::path sets = out / "bodies" / rec.stem() / "patterns";
    for (const auto& [name, n] : pieces) {
      SCOPED_TRACE(rec.stem().string() + " " + name);
      const auto& p = j["patterns"][name];
      EXPECT_EQ(p["pieces"].get<std::size_t>(), n);
      EXPECT_EQ(p["flipped"].get<std::size_t>(), 0u);
      // The sewability figures are there (their size is the library's test:
      // tests/systems/pattern/made_to_measure_test.cpp).
      EXPECT_GE(p["max_seam_difference_mm"].get<double>(), 0.0);
      EXPECT_LE(p["failed_seams"].get<std::size_t>(), p["seams_opened"].get<std::size_t>() + 8);
      // One body: one-shot (the batch form pays off from 8 bodies), no piece warm.
      EXPECT_EQ(p["warm_started_pieces"].get<std::size_t>(), 0u);
      std::size_t svg = 0;
      for (const auto& e : fs::directory_iterator(sets / name)) {
        svg += e.path().extension() == ".svg";
        written[e.path()] = fs::last_write_time(e.path());
        EXPECT_NE(e.path().filename().string().rfind(".tmp"), 0u);  // no temporary left
      }
      EXPECT_EQ(svg, n);
      ASSERT_TRUE(fs::exists(sets / name / "pattern.dxf"));
      const std::string csv = read_bytes(sets / name / "measurements.csv");
      EXPECT_EQ(csv.rfind("piece,kind,name,pattern_mm,body_mm\n", 0), 0u);
      EXPECT_NE(csv.find(",width,middle,"), std::string::npos);
      EXPECT_NE(csv.find(",seam,joint"), std::string::npos);
    }
  }
  // The merged report carries the pattern figures.
  const auto rep = nlohmann::json::parse(read_bytes(out / "report.json"));
  ASSERT_EQ(rep["bodies"].size(), 1u);
  EXPECT_TRUE(rep["bodies"][0].contains("patterns"));
  // A rerun redoes nothing: every body was complete.
  const CliRun again = run_cli("--threads 2 regen" + template_args() + " --count 1 --patterns --out " + out.string());
  ASSERT_EQ(again.code, 0) << again.out;
  const auto timing = nlohmann::json::parse(read_bytes(out / "timing.json"));
  EXPECT_EQ(timing["skipped_complete"].get<std::size_t>(), 1u);
  EXPECT_EQ(timing["regenerated_now"].get<std::size_t>(), 0u);
  for (const auto& [p, t] : written) EXPECT_EQ(fs::last_write_time(p), t) << p;
}

TEST(RegenPatternsCli, TheTopIsCutAlongItsMarkedSeamsUnlessTold) {
  // The encoded top template carries its seam marks (template JSON edge
  // flags): five pieces (front and back body and yoke, collar), all seams
  // sewable; with --no-marked-seams the top is one piece plus the collar.
  const std::string top = " --template " + (encoded_templates() / "top.template.json").string();
  for (const bool marked : {true, false}) {
    SCOPED_TRACE(marked ? "marked" : "--no-marked-seams");
    const fs::path out = atelier::testing::scratch_dir(marked ? "regen_top_marked" : "regen_top_unmarked");
    const CliRun r = run_cli("regen" + top + " --count 1 --patterns" + (marked ? "" : " --no-marked-seams") +
                             " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    const auto recs = records(out);
    ASSERT_EQ(recs.size(), 1u);
    const auto p = nlohmann::json::parse(read_bytes(recs[0]))["patterns"]["top"];
    EXPECT_EQ(p["pieces"].get<std::size_t>(), marked ? 5u : 2u);
    EXPECT_EQ(p["flipped"].get<std::size_t>(), 0u);
    if (marked) {
      EXPECT_LT(p["max_seam_difference_mm"].get<double>(), 2.0);
    }
  }
}

TEST(RegenPatternsCli, PatternsAfterARunWithoutThemRedoTheBodies) {
  const fs::path out = atelier::testing::scratch_dir("regen_patterns_late");
  const std::string skirt = " --template " + (encoded_templates() / "skirt.template.json").string();
  const CliRun a = run_cli("regen" + skirt + " --count 2 --out " + out.string());
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_FALSE(fs::exists(out / "bodies" / records(out)[0].stem() / "patterns"));
  const CliRun b = run_cli("regen" + skirt + " --count 2 --patterns --out " + out.string());
  ASSERT_EQ(b.code, 0) << b.out;
  const auto timing = nlohmann::json::parse(read_bytes(out / "timing.json"));
  EXPECT_EQ(timing["regenerated_now"].get<std::size_t>(), 2u);
  for (const fs::path& rec : records(out)) {
    EXPECT_TRUE(nlohmann::json::parse(read_bytes(rec)).contains("patterns")) << rec;
    EXPECT_TRUE(fs::exists(out / "bodies" / rec.stem() / "patterns" / "skirt" / "measurements.csv"));
  }
}

TEST(RegenPatternsCli, BatchPatternSetsAreTheSameBitsForAnyThreadCountAndChunk) {
  // A job of 8 bodies makes its pattern sets with the batch form (prepared
  // on the templates regenerated on the reference body, each body warm
  // from it): every file is the same bytes on 1 thread in one chunk and on
  // 2 threads in chunks of 3 (bodies in another order on the workers).
  const std::string args = template_args({"skirt", "top"}) + " --count 8 --patterns";
  const fs::path a = atelier::testing::scratch_dir("regen_patterns_t1");
  const fs::path b = atelier::testing::scratch_dir("regen_patterns_t2");
  const CliRun ra = run_cli("--threads 1 regen" + args + " --out " + a.string());
  ASSERT_EQ(ra.code, 0) << ra.out;
  const CliRun rb = run_cli("--threads 2 regen" + args + " --chunk 3 --out " + b.string());
  ASSERT_EQ(rb.code, 0) << rb.out;
  const auto recs = records(a);
  ASSERT_EQ(recs.size(), 8u);
  std::size_t files = 0;
  for (const fs::path& rec : recs) {
    const auto j = nlohmann::json::parse(read_bytes(rec));
    ASSERT_TRUE(j.value("ok", false)) << j.dump();
    // The batch form: pieces started warm from the reference's pattern.
    EXPECT_GE(j["patterns"]["top"]["warm_started_pieces"].get<std::size_t>(), 1u) << rec;
    EXPECT_EQ(j["patterns"], nlohmann::json::parse(read_bytes(b / "bodies" / rec.filename()))["patterns"]) << rec;
    for (const auto& e : fs::recursive_directory_iterator(a / "bodies" / rec.stem() / "patterns")) {
      if (!e.is_regular_file()) continue;
      const fs::path other = b / fs::relative(e.path(), a);
      ASSERT_TRUE(fs::exists(other)) << other;
      EXPECT_EQ(read_bytes(e.path()), read_bytes(other)) << e.path();
      ++files;
    }
  }
  EXPECT_EQ(files, 8u * (1 + 5 + 2 + 2));  // SVG per piece (skirt 1, top 5), DXF and CSV per set
}
