// The MakeHuman readers (io/makehuman) on bad input, issue 27: numbers out
// of range, byte-order marks, files with nothing in them, whitespace-only
// lines in a .mhclo `verts` section, JSON of the wrong shape.
#include <atelier/io/makehuman/makehuman.h>
#include <atelier/io/makehuman/mhclo.h>
#include <gtest/gtest.h>

#include <bit>
#include <charconv>

#include "io_test_support.h"

using namespace atelier;
using namespace atelier::makehuman;
using namespace atelier::test;

namespace {
const std::string kUtf8Bom = "\xEF\xBB\xBF";
const std::string kMhclo =
    "name shirt\nobj_file shirt.obj\nx_scale 1 2 1.5\nverts 0\n1 2 3 0.2 0.3 0.5 0.01 -0.02 0.03\n7\n"
    "4 5 6 1 0 0 0 0 0\ndelete_verts\n1 2 - 4\n";
}  // namespace

TEST(MakeHumanIo, MhcloWhitespaceOnlyLineInsideVertsIsSkipped) {
  // MakeHuman's own reader skips a line with no word wherever it is; ours
  // ended the `verts` section there and refused the next binding line.
  const GarmentBinding plain = parse_mhclo(kMhclo, "plain.mhclo", 100);
  std::string spaced = kMhclo;
  spaced.insert(spaced.find("7\n"), " \t \r\n");
  const GarmentBinding b = parse_mhclo(spaced, "spaced.mhclo", 100);
  ASSERT_EQ(b.refs.size(), 3u);
  ASSERT_EQ(plain.refs.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(b.refs[i].v, plain.refs[i].v);
    EXPECT_EQ(b.refs[i].w, plain.refs[i].w);
    EXPECT_EQ(b.refs[i].offset, plain.refs[i].offset);
  }
  EXPECT_EQ(b.delete_verts, (std::vector<std::uint32_t>{1, 2, 3, 4}));
  EXPECT_EQ(parse_mhclo(kUtf8Bom + kMhclo, "bom.mhclo", 100).name, "shirt");
}

TEST(MakeHumanIo, MhcloNumbersAreCheckedWhole) {
  auto bad = [](const std::string& line, const std::vector<std::string>& frags) {
    expect_error([&] { (void)parse_mhclo("verts 0\n" + line + "\n", "b.mhclo", 100); }, ErrorCode::kParse, frags);
  };
  bad("1 2 3 0.2 0.3 0.5 1e400 0 0", {"b.mhclo:2", "'1e400'", "out of the range"});
  bad("1e300 2 3 0.2 0.3 0.5 0 0 0", {"b.mhclo:2", "not a vertex index"});  // was cast to long long: UB
  bad("1.5", {"b.mhclo:2", "not a vertex index"});                          // was truncated to 1
  bad("1 2 3 0.2 0.3 nan 0 0 0", {"b.mhclo:2", "non-finite"});
  bad("1 2 300 0.2 0.3 0.5 0 0 0", {"b.mhclo:2", "vertex index 300 out of range"});
  bad("99999999999999999999", {"b.mhclo:2", "out of range"});
  expect_error([] { (void)parse_mhclo("x_scale 1 2 inf\nverts 0\n1\n", "s.mhclo", 100); }, ErrorCode::kParse,
               {"s.mhclo:1", "non-finite"});
  expect_error([] { (void)parse_mhclo("just some text\n", "t.mhclo", 100); }, ErrorCode::kParse,
               {"t.mhclo", "no 'verts' section"});
}

TEST(MakeHumanIo, TargetsRefuseOutOfRangeNumbersAndAcceptEmptyTargets) {
  const Target t = parse_target(kUtf8Bom + "# c\n3 0.5 -0.25 1\n", "dir/a-b.target", 10);
  EXPECT_EQ(t.name, "a-b");
  EXPECT_EQ(t.index, (std::vector<std::uint32_t>{3}));
  expect_error([] { (void)parse_target("3 1e39 0 0\n", "f.target", 10); }, ErrorCode::kParse,
               {"f.target:1", "out of the range of a float"});
  expect_error([] { (void)parse_target("99999999999 0 0 0\n", "i.target", 10); }, ErrorCode::kParse,
               {"i.target:1", "out of range"});
  // MakeHuman ships targets that are a comment header only (the neutral blend).
  EXPECT_TRUE(parse_target("# only a comment\n\n", "e.target", 10).index.empty());
  expect_error([] { (void)parse_target("hello\n", "h.target", 10); }, ErrorCode::kParse, {"h.target:1"});
}

TEST(MakeHumanIo, BaseMeshRefusesNoGeometryAndSkipsTheMark) {
  const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng body\nf 1 2 3 4\n";
  const BaseMesh a = parse_base_mesh(quad, "q.obj"), b = parse_base_mesh(kUtf8Bom + quad, "qb.obj");
  EXPECT_EQ(b.positions, a.positions);
  ASSERT_EQ(b.groups.size(), 1u);
  EXPECT_EQ(b.groups[0].face_nodes, a.groups[0].face_nodes);
  expect_error([] { (void)parse_base_mesh("hello\n", "t.obj"); }, ErrorCode::kParse, {"t.obj", "no vertex"});
  expect_error([] { (void)parse_base_mesh("v 0 0 0\nv 1 0 0\n", "p.obj"); }, ErrorCode::kParse, {"p.obj", "no face"});
  expect_error([] { (void)parse_base_mesh("v 0 1e39 0\n", "r.obj"); }, ErrorCode::kParse,
               {"r.obj:1", "out of the range of a float"});
}

TEST(MakeHumanIo, ModifierJsonOfTheWrongShapeIsAParseErrorNamingThePlace) {
  const auto mods = parse_measure_modifiers(
      R"([{"group": "measure", "modifiers": [{"target": "measure-neck", "min": "d", "max": "i"}, {"label": "x"}, {"target": "measure-waist"}]}, {"group": "none"}])",
      "m.json");
  ASSERT_EQ(mods.size(), 2u);
  EXPECT_EQ(mods[0].target, "measure-neck");
  EXPECT_EQ(mods[0].min, "d");
  EXPECT_EQ(mods[1].min, "decr");
  EXPECT_EQ(mods[1].max, "incr");
  // These escaped as nlohmann::json::type_error (no file, no place).
  expect_error([] { (void)parse_measure_modifiers("[1, 2]", "a.json"); }, ErrorCode::kParse, {"a.json", "/0"});
  expect_error([] { (void)parse_measure_modifiers(R"([{"modifiers": 3}])", "b.json"); }, ErrorCode::kParse,
               {"b.json", "/0/modifiers"});
  expect_error([] { (void)parse_measure_modifiers(R"([{"modifiers": [{"target": 5}]}])", "c.json"); },
               ErrorCode::kParse, {"c.json", "/0/modifiers/0/target", "string"});
  expect_error([] { (void)parse_measure_modifiers("{", "d.json"); }, ErrorCode::kParse, {"d.json"});
  expect_error([] { (void)parse_measures(R"({"measures": {"w": [1, -2]}})", "e.json", 10); }, ErrorCode::kParse,
               {"e.json", "invalid vertex index"});
}

// Found by the mh_modifiers harness: a number beyond a double made
// nlohmann throw out_of_range (406), which escaped both JSON readers.
TEST(MakeHumanIo, JsonNumbersBeyondADoubleAreRefusedNamingTheFile) {
  for (const char* text : {"[{\"group\": 777E377777777777777777}]", "{\"measures\": {\"a\": [1e999]}}"}) {
    try {
      if (text[0] == '[')
        (void)atelier::makehuman::parse_measure_modifiers(text, "modifiers.json");
      else
        (void)atelier::makehuman::parse_measures(text, "measures.json", 10);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const atelier::Error& e) {
      EXPECT_NE(std::string(e.what()).find(text[0] == '[' ? "modifiers.json" : "measures.json"), std::string::npos)
          << e.what();
    }
  }
}

TEST(MakeHumanIo, TargetNumbersAreExactlyThoseOfFromChars) {
  // The targets' reader parses short decimals by itself (issue 26: start-up
  // time); every value must be the float std::from_chars gives, bit for bit,
  // including the forms that fall back to it (exponents, long mantissas,
  // -0, a trailing point, leading zeros).
  std::vector<std::string> words = {".026",         "-.166",       "0",        "-0",       "-.000",
                                    "5.",           "007.50",      "16777216", "16777217", "16777215",
                                    "123456789",    ".1234567891", "1e-3",     "-2.5E2",   "0.0000000001",
                                    "3.4028235e38", "0.1",         "0.3",      "-0.7",     "1.0000001"};
  std::uint64_t s = 0x9e3779b97f4a7c15ull;
  auto next = [&] {
    s ^= s << 13, s ^= s >> 7, s ^= s << 17;
    return s;
  };
  for (int k = 0; k < 20000; ++k) {  // random decimals of 1-9 digits, 0-10 of them after the point
    const int digits = 1 + static_cast<int>(next() % 9), frac = static_cast<int>(next() % 11);
    std::string w = next() % 2 ? "-" : "";
    std::string d;
    for (int i = 0; i < digits; ++i) d += static_cast<char>('0' + next() % 10);
    if (frac > 0 && frac <= digits)
      d.insert(d.size() - static_cast<std::size_t>(frac), ".");
    else if (frac > digits)
      d = "." + std::string(static_cast<std::size_t>(frac - digits), '0') + d;
    words.push_back(w + d);
  }
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += "1 " + words[i] + " 0 " + words[i] + "\r\n";
  const Target t = parse_target(text, "r.target", 10);
  ASSERT_EQ(t.delta.size(), words.size());
  for (std::size_t i = 0; i < words.size(); ++i) {
    float want = 0;
    const auto [q, ec] = std::from_chars(words[i].data(), words[i].data() + words[i].size(), want);
    ASSERT_EQ(ec, std::errc{}) << words[i];
    ASSERT_EQ(q, words[i].data() + words[i].size()) << words[i];
    EXPECT_EQ(std::bit_cast<std::uint32_t>(t.delta[i].x()), std::bit_cast<std::uint32_t>(want)) << words[i];
    EXPECT_EQ(std::bit_cast<std::uint32_t>(t.delta[i].z()), std::bit_cast<std::uint32_t>(want)) << words[i];
  }
  for (const char* bad : {"1 - 0 0\n", "1 . 0 0\n", "1 1.2.3 0 0\n", "1 0x1 0 0\n", "1 +1 0 0\n"})
    expect_error([&] { (void)parse_target(bad, "b.target", 10); }, ErrorCode::kParse, {"b.target:1"});
}
