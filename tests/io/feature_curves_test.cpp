// Feature-curve files (issue 26, io/feature_curves.h): what is read, exact
// round trips, and a clean error naming the file and line (and the curve
// and point) for every kind of malformed input; no input makes the reader
// throw or crash.
#include <atelier/io/feature_curves.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "io_test_support.h"

using namespace atelier;
using namespace atelier::test;

namespace {

const char* kGood = R"({
  "units": "cm",
  "up": "z",
  "curves": [
    {"name": "waist", "closed": true,
     "points": [[10, 0, 100], [0, 8, 100.5], [-10, 0, 1e2], [0, -8, 99.75], [10, 0, 100]]},
    {"name": "centre_front", "closed": false, "points": [[0, -8, 120], [0, -8.5, -80.25E-1]]}
  ]
})";

/// The error of a malformed text; expects a kParse naming "c.json:<line>".
std::string error_of(const std::string& text, int line) {
  auto r = parse_feature_curves(text, "c.json");
  EXPECT_FALSE(r) << "accepted: " << text;
  if (r) return {};
  EXPECT_EQ(r.status().code(), ErrorCode::kParse);
  const std::string want = "c.json:" + std::to_string(line) + ":";
  EXPECT_EQ(r.status().message().rfind(want, 0), 0u) << r.status().message() << " (want line " << line << ")";
  return r.status().message();
}

std::string curve(const std::string& name, const std::string& closed, const std::string& points) {
  return "{\"curves\": [\n{\"name\": \"" + name + "\", \"closed\": " + closed + ",\n \"points\": " + points + "}]}";
}

}  // namespace

TEST(FeatureCurveFile, ReadsNamesUnitsAxesAndPoints) {
  auto r = parse_feature_curves(kGood, "c.json");
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_TRUE(r->has_units);
  EXPECT_EQ(r->scale, 0.01);
  EXPECT_TRUE(r->has_up);
  EXPECT_TRUE(r->up_z);
  ASSERT_EQ(r->curves.size(), 2u);
  const auto& w = r->curves[0];
  EXPECT_EQ(w.name, "waist");
  EXPECT_TRUE(w.closed);
  // The closing repeat of the first point is dropped.
  ASSERT_EQ(w.points.size(), 4u);
  EXPECT_EQ(w.points[1], Vec3d(0, 8, 100.5));
  EXPECT_EQ(w.points[2], Vec3d(-10, 0, 100));
  EXPECT_EQ(w.line, 5u);
  EXPECT_EQ(w.point_lines[0], 6u);
  const auto& f = r->curves[1];
  EXPECT_FALSE(f.closed);
  EXPECT_EQ(f.points[1], Vec3d(0, -8.5, -8.025));
  EXPECT_EQ(f.point_lines[1], 7u);
  // Units and axes are optional: then the body's are meant.
  auto bare = parse_feature_curves(curve("hip", "true", "[[0,0,0],[1,0,0],[0,1,0]]"), "c.json");
  ASSERT_TRUE(bare) << bare.status().to_string();
  EXPECT_FALSE(bare->has_units);
  EXPECT_FALSE(bare->has_up);
}

TEST(FeatureCurveFile, WritesWhatItReadsBitForBit) {
  TempDir d;
  auto r = parse_feature_curves(kGood, "c.json");
  ASSERT_TRUE(r);
  FeatureCurveFile f = *r;
  // Coordinates that need all 17 digits.
  f.curves[1].points.push_back(Vec3d(0.1 + 0.2, -1.0 / 3.0, std::nextafter(1.0, 2.0)));
  write_feature_curves(f, d.path() / "c.json");
  auto back = read_feature_curves(d.path() / "c.json");
  ASSERT_TRUE(back) << back.status().to_string();
  ASSERT_EQ(back->curves.size(), f.curves.size());
  EXPECT_EQ(back->scale, f.scale);
  EXPECT_EQ(back->up_z, f.up_z);
  for (std::size_t c = 0; c < f.curves.size(); ++c) {
    EXPECT_EQ(back->curves[c].name, f.curves[c].name);
    EXPECT_EQ(back->curves[c].closed, f.curves[c].closed);
    EXPECT_EQ(back->curves[c].points, f.curves[c].points);
  }
  // What the reader refuses is not written (and nothing is left behind).
  f.curves[0].points[0].x() = std::nan("");
  EXPECT_THROW(write_feature_curves(f, d.path() / "bad.json"), Error);
  EXPECT_FALSE(std::filesystem::exists(d.path() / "bad.json"));
  auto missing = read_feature_curves(d.path() / "none.json");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.status().code(), ErrorCode::kIo);
  EXPECT_NE(missing.status().message().find("none.json"), std::string::npos);
}

TEST(FeatureCurveFile, NamesTheLineCurveAndPointOfEveryMalformedInput) {
  // Syntax.
  EXPECT_NE(error_of("", 1).find("empty"), std::string::npos);
  EXPECT_NE(error_of("{\"curves\": [\n{\"name\": \"waist\",\n \"closed\": true,\n \"points\": [[1,2,3],[NaN, 1, 2]]", 4)
                .find("NaN"),
            std::string::npos);
  error_of("{\"curves\": [1, 2\n", 2);                       // unterminated
  error_of("{\"curves\": []}\n\nx", 3);                      // trailing text
  error_of("{\"curves\": [], \"curves\": []}", 1);           // duplicate key
  error_of(std::string(40, '[') + std::string(40, ']'), 1);  // nesting
  error_of("{\"curves\": [{\"name\": \"wa\nist\"}]}", 1);    // line break in a string
  error_of("{\"curves\": [01]}", 1);                         // leading zero
  // Types and values.
  EXPECT_NE(error_of("[1, 2]", 1).find("not an object"), std::string::npos);
  EXPECT_NE(error_of("{\"curves\": {}}", 1).find("not an array"), std::string::npos);
  EXPECT_NE(error_of("{\"curves\": []}", 1).find("empty"), std::string::npos);
  EXPECT_NE(error_of("{\"units\": \"in\", \"curves\": []}", 1).find("units"), std::string::npos);
  EXPECT_NE(error_of("{\"up\": \"x\", \"curves\": []}", 1).find("up"), std::string::npos);
  EXPECT_NE(error_of("{\"curves\": [], \"colour\": 1}", 1).find("unknown key \"colour\""), std::string::npos);
  std::string m = error_of(curve("waistline", "true", "[[0,0,0],[1,0,0],[0,1,0]]"), 2);
  EXPECT_NE(m.find("unknown curve name \"waistline\""), std::string::npos) << m;
  EXPECT_NE(m.find("centre_front"), std::string::npos) << m;  // the names are listed
  m = error_of(curve("waist", "1", "[[0,0,0],[1,0,0],[0,1,0]]"), 2);
  EXPECT_NE(m.find("\"closed\" is a number"), std::string::npos) << m;
  m = error_of(curve("waist", "true", "[[0,0,0],[1,0,0],\n[0,\"1\",0]]"), 4);
  EXPECT_NE(m.find("curve 'waist', point 2: coordinate 1 is a string"), std::string::npos) << m;
  m = error_of(curve("waist", "true", "[[0,0,0],\n[1,0],[0,1,0]]"), 4);
  EXPECT_NE(m.find("point 1: expected [x, y, z]"), std::string::npos) << m;
  m = error_of(curve("waist", "true", "[[0,0,0],[1,0,0],\n\n[0,1e400,0]]"), 5);
  EXPECT_NE(m.find("point 2: coordinate 1 is out of range"), std::string::npos) << m;
  m = error_of(curve("waist", "true", "[[0,0,0],[1,0,0],[0,0,0]]"), 3);
  EXPECT_NE(m.find("closed curve needs at least 3"), std::string::npos) << m;
  m = error_of(curve("centre_front", "false", "[[0,0,0]]"), 3);
  EXPECT_NE(m.find("open curve needs at least 2"), std::string::npos) << m;
  m = error_of(curve("centre_front", "false", "[[0,0,0],\n[0,0,0]]"), 4);
  EXPECT_NE(m.find("repeats the point before it"), std::string::npos) << m;
  m = error_of(
      "{\"curves\": [\n{\"name\": \"hip\", \"closed\": true, \"points\": [[0,0,0],[1,0,0],[0,1,0]]},\n"
      "{\"name\": \"hip\", \"closed\": true, \"points\": [[0,0,0],[1,0,0],[0,1,0]]}]}",
      3);
  EXPECT_NE(m.find("curve 'hip' is given twice (first at line 2)"), std::string::npos) << m;
  m = error_of("{\"curves\": [\n{\"name\": \"hip\", \"points\": []}]}", 2);
  EXPECT_NE(m.find("no \"closed\""), std::string::npos) << m;
}

TEST(FeatureCurveFile, MutatedFilesAreReadOrRefusedNeverThrown) {
  // A small deterministic fuzz of the good file (the libFuzzer harness,
  // fuzz/feature_curves_fuzz.cpp, runs the real thing).
  std::mt19937 rng(26);
  const std::string good = kGood;
  const std::string alphabet = "{}[],:\"0123456789.eE+-truefalsnNaI \n";
  std::size_t accepted = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string s = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % s.size();
      switch (rng() % 3) {
        case 0:
          s[at] = alphabet[rng() % alphabet.size()];
          break;
        case 1:
          s.erase(at, 1 + rng() % 8);
          break;
        default:
          s.insert(at, 1, alphabet[rng() % alphabet.size()]);
      }
      if (s.empty()) s = "{";
    }
    Expected<FeatureCurveFile> r = Status{};
    ASSERT_NO_THROW(r = parse_feature_curves(s, "c.json")) << s;
    if (r) {
      ++accepted;
      for (const auto& c : r->curves)
        for (const auto& p : c.points) ASSERT_TRUE(p.allFinite()) << s;
    } else {
      ASSERT_EQ(r.status().message().rfind("c.json", 0), 0u) << r.status().message();
    }
  }
  EXPECT_GT(accepted, 0u);  // some edits (inside numbers, whitespace) keep it valid
}
