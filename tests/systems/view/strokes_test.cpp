// Stroke files (systems/view/strokes.h): exact round trip, and every kind of
// malformed input refused with the file name and the JSON location.
#include <atelier/systems/view/strokes.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "support/run_command.h"

namespace atelier {
namespace {

StrokeFile sample_file() {
  StrokeFile f;
  f.camera = Camera::look_at(Vec3d(0.3, 1.2, 2.5), Vec3d(0, 1, 0), Vec3d::UnitY(), 35.0, 640, 480);
  Stroke paint;
  paint.points = {{10.125, 20.5}, {100.0 / 3.0, 40.0}, {300.7, 1e-7}};
  paint.tool = StrokeTool::kPaint;
  paint.name = "neckline";
  Stroke through;
  through.points = {{0.5, 0.5}, {639.5, 479.5}};
  through.tool = StrokeTool::kPaintThrough;
  through.through = true;
  Stroke cut;
  cut.points = {{1, 2}, {3, 4}, {5, 7}};
  cut.tool = StrokeTool::kCut;
  cut.through = true;
  Stroke pick;
  pick.points = {{320.25, 240.75}};
  pick.tool = StrokeTool::kPick;
  Stroke part;
  part.points = {{1, 1}, {2, 3}};
  part.tool = StrokeTool::kPartition;
  f.strokes = {paint, through, cut, pick, part};
  return f;
}

/// The valid sample as text, with `from` replaced by `to` once.
std::string variant(const std::string& from, const std::string& to) {
  std::string t = strokes_to_json(sample_file()).value();
  const auto at = t.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) t.replace(at, from.size(), to);
  return t;
}

std::string minimal(const std::string& strokes, const std::string& camera_extra = "") {
  return R"({"camera": {"view": [1,0,0,0, 0,1,0,0, 0,0,1,-5, 0,0,0,1],
     "projection": [1,0,0,0, 0,1,0,0, 0,0,-0.1,0, 0,0,0,1], "viewport": [800, 600])" +
         camera_extra + "},\n \"strokes\": " + strokes + "}";
}

void expect_refused(const std::string& text, const std::string& where, const std::string& what = "") {
  auto r = parse_strokes(text, "bad.json");
  ASSERT_FALSE(r) << text;
  EXPECT_EQ(r.status().code(), ErrorCode::kParse);
  const std::string msg = r.status().message();
  EXPECT_EQ(msg.rfind("bad.json", 0), 0u) << msg;
  EXPECT_NE(msg.find(where), std::string::npos) << "expected '" << where << "' in: " << msg;
  if (!what.empty()) {
    EXPECT_NE(msg.find(what), std::string::npos) << "expected '" << what << "' in: " << msg;
  }
}

TEST(Strokes, RoundTripIsExact) {
  const StrokeFile f = sample_file();
  auto text = strokes_to_json(f);
  ASSERT_TRUE(text) << text.status().to_string();
  auto back = parse_strokes(*text, "mem");
  ASSERT_TRUE(back) << back.status().to_string();
  EXPECT_EQ(back->camera.view, f.camera.view);
  EXPECT_EQ(back->camera.projection, f.camera.projection);
  EXPECT_EQ(back->camera.width, 640);
  EXPECT_EQ(back->camera.height, 480);
  ASSERT_EQ(back->strokes.size(), f.strokes.size());
  for (std::size_t i = 0; i < f.strokes.size(); ++i) {
    EXPECT_EQ(back->strokes[i].points, f.strokes[i].points) << i;  // bit-identical doubles
    EXPECT_EQ(back->strokes[i].tool, f.strokes[i].tool) << i;
    EXPECT_EQ(back->strokes[i].through, f.strokes[i].through) << i;
    EXPECT_EQ(back->strokes[i].name, f.strokes[i].name) << i;
  }
  // Through the file system, atomically.
  const auto dir = testing::scratch_dir("strokes_roundtrip");
  ASSERT_TRUE(write_strokes(f, dir / "s.json"));
  auto again = read_strokes(dir / "s.json");
  ASSERT_TRUE(again) << again.status().to_string();
  EXPECT_EQ(again->strokes[1].points, f.strokes[1].points);
}

TEST(Strokes, ToolSpellings) {
  auto r = parse_strokes(minimal(R"([{"points": [[0,0],[1,1]], "tool": "paint", "through": true},
                                      {"points": [[0,0],[1,1]], "tool": "cut"},
                                      {"points": [[5,5]], "tool": "pick"}])"),
                         "ok.json");
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_EQ(r->strokes[0].tool, StrokeTool::kPaintThrough);  // "paint" + through
  EXPECT_FALSE(r->strokes[1].through);                       // the default
  EXPECT_STREQ(to_string(StrokeTool::kPartition), "partition");
}

TEST(Strokes, MissingKeysAndWrongTypesNameTheLocation) {
  expect_refused(R"({"strokes": []})", "at /", "missing key \"camera\"");
  expect_refused(R"({"camera": {"view": [], "projection": [], "viewport": [1,1]}})", "at /", "\"strokes\"");
  expect_refused(minimal("[]").replace(minimal("[]").find("\"viewport\""), 10, "\"viewpart\""), "/camera");
  expect_refused(minimal(R"([{"tool": "paint"}])"), "/strokes/0", "missing key \"points\"");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]]}])"), "/strokes/0", "missing key \"tool\"");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]], "tool": "brush"}])"), "/strokes/0/tool", "unknown tool");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]], "tool": 3}])"), "/strokes/0/tool", "expected a string");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]], "tool": "cut", "thru": true}])"), "/strokes/0/thru",
                 "unknown key");
  expect_refused(minimal(R"([{"points": [[0,0],[1,"2"]], "tool": "cut"}])"), "/strokes/0/points/1/1",
                 "expected a number");
  expect_refused(minimal(R"([{"points": [[0,0],[1,2,3]], "tool": "cut"}])"), "/strokes/0/points/1", "expected a point");
  expect_refused(minimal(R"({"points": []})"), "/strokes", "expected an array");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]], "tool": "cut", "through": "yes"}])"), "/strokes/0/through",
                 "true or false");
  expect_refused(variant("\"view\": [", "\"view\": [1,"), "/camera/view", "16 numbers");
  expect_refused(variant("\"viewport\": [", "\"viewport\": [0, "), "/camera/viewport", "[width, height]");
}

TEST(Strokes, BadNumbersAndCamerasAreRefused) {
  // NaN and Infinity are not JSON; other writers produce them anyway.
  expect_refused(minimal(R"([{"points": [[0,NaN],[1,1]], "tool": "paint"}])"), "bad.json:", "non-finite number 'NaN'");
  expect_refused(minimal(R"([{"points": [[0,-Infinity],[1,1]], "tool": "paint"}])"),
                 "bad.json:", "non-finite number '-Infinity'");
  expect_refused(minimal(R"([{"points": [[0,1e999],[1,1]], "tool": "paint"}])"), "bad.json:", "1e999");
  expect_refused(minimal(R"([{"points": [[0,1e12],[1,1]], "tool": "paint"}])"), "/strokes/0/points/0/1", "beyond");
  // A singular camera: a projection that flattens everything.
  std::string sing = minimal("[]");
  sing.replace(sing.find("0,0,-0.1,0"), 10, "0,0,0,0");
  sing.replace(sing.find("0,0,0,1]"), 8, "0,0,0,0]");
  expect_refused(sing, "/camera", "singular");
  expect_refused(variant("\"viewport\": [", "\"viewport\": [-3, 2, "), "/camera/viewport");
  std::string frac = minimal("[]");
  frac.replace(frac.find("[800, 600]"), 10, "[800.5, 600]");
  expect_refused(frac, "/camera/viewport/0", "whole number");
}

TEST(Strokes, TooFewPointsAndMisplacedPicks) {
  expect_refused(minimal(R"([{"points": [[0,0]], "tool": "paint"}])"), "/strokes/0/points", "at least 2");
  expect_refused(minimal(R"([{"points": [], "tool": "partition"}])"), "/strokes/0/points", "at least 2");
  expect_refused(minimal(R"([{"points": [[3,4],[3,4],[3,4]], "tool": "cut"}])"), "/strokes/0/points", "all equal");
  expect_refused(minimal(R"([{"points": [[3,4],[5,6]], "tool": "pick"}])"), "/strokes/0/points", "exactly one");
  expect_refused(minimal(R"([{"points": [[3,4]], "tool": "pick"}])"), "/strokes/0", "must follow a cut");
  expect_refused(minimal(R"([{"points": [[0,0],[1,1]], "tool": "paint"}, {"points": [[3,4]], "tool": "pick"}])"),
                 "/strokes/1", "must follow a cut");
  expect_refused(
      minimal(R"([{"points": [[0,0],[1,1]], "tool": "cut"}, {"points": [[3,4]], "tool": "pick", "through": true}])"),
      "/strokes/1/through");
}

TEST(Strokes, SyntaxErrorsNameLineAndColumn) {
  expect_refused("", "bad.json:1:1", "invalid JSON");
  expect_refused("{\"camera\": {\n  \"view\": [1, 2,,]}}", "bad.json:2:", "invalid JSON");
  expect_refused(minimal("[").substr(0, 60), "truncated");
  std::string deep(100, '[');
  expect_refused(deep, "bad.json:1:17", "nested deeper");
  expect_refused(std::string("\xff\xfe\x00garbage", 10), "bad.json:", "invalid JSON");
  // The size limit is checked before parsing.
  auto r = parse_strokes(minimal("[]"), "big.json", {.max_bytes = 16});
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("limit"), std::string::npos);
  auto io = read_strokes("/nonexistent/strokes.json");
  ASSERT_FALSE(io);
  EXPECT_EQ(io.status().code(), ErrorCode::kIo);
  EXPECT_NE(io.status().message().find("/nonexistent/strokes.json"), std::string::npos);
}

// The parser is a fuzzing entry point: random damage to a valid file never
// crashes it, and it either reads a file or refuses it naming the file.
TEST(Strokes, RandomDamageIsRefusedCleanly) {
  const std::string good = strokes_to_json(sample_file()).value();
  std::mt19937 rng(7);
  std::size_t accepted = 0;
  for (int k = 0; k < 3000; ++k) {
    std::string t = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % t.size();
      switch (rng() % 3) {
        case 0:
          t[at] = static_cast<char>(rng() % 256);
          break;
        case 1:
          t.erase(at, 1 + rng() % 8);
          break;
        default:
          t.insert(at, 1, "[]{},:\"0e-.aN"[rng() % 13]);
          break;
      }
      if (t.empty()) t = "{";
    }
    auto r = parse_strokes(t, "fuzz.json");
    if (r) {
      ++accepted;
      ASSERT_TRUE(r->camera.check());
      for (const Stroke& s : r->strokes)
        for (const Vec2d& p : s.points) ASSERT_TRUE(p.allFinite());
    } else {
      ASSERT_EQ(r.status().code(), ErrorCode::kParse);
      ASSERT_EQ(r.status().message().rfind("fuzz.json", 0), 0u) << r.status().message();
    }
  }
  EXPECT_LT(accepted, 3000u);  // damage is mostly noticed
}

}  // namespace
}  // namespace atelier
