// Template files (issue #4): the three project templates survive a JSON
// round trip table for table and bit for bit (encodings, profiles, decoded
// nodes, regenerated garments), and every kind of broken file is refused
// with an Error naming the file, the JSON location and the problem.
#include <atelier/storage/validate.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/feature_encoding.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/profile/template_json.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/project_templates.h"

using namespace atelier;
namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

using Fixture = atelier::testing::TemplateFixture;
using atelier::testing::template_fixture;

fs::path scratch() {
  const char* env = std::getenv("ATELIER_TMP");
  fs::path d = (env ? fs::path(env) : fs::temp_directory_path() / "atelier-tests") / "template_json";
  fs::create_directories(d);
  return d;
}

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}
bool same_bits(const Vec3d& a, const Vec3d& b) {
  return std::memcmp(a.data(), b.data(), 3 * sizeof(double)) == 0;
}

void expect_same_template(const ProfileTemplate& a, const ProfileTemplate& b) {
  EXPECT_EQ(diff_tables(a.model, b.model), "");
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_TRUE(same_bits(a.clearance, b.clearance));
  EXPECT_EQ(a.levels, b.levels);
  EXPECT_EQ(a.node_names, b.node_names);
  ASSERT_EQ(a.encoded_clearance.size(), b.encoded_clearance.size());
  for (std::size_t i = 0; i < a.encoded_clearance.size(); ++i)
    EXPECT_TRUE(same_bits(a.encoded_clearance[i], b.encoded_clearance[i])) << "node " << i;
  ASSERT_EQ(a.encodings.nodes.size(), b.encodings.nodes.size());
  for (std::size_t i = 0; i < a.encodings.nodes.size(); ++i) {
    const NodeEncoding &x = a.encodings.nodes[i], &y = b.encodings.nodes[i];
    EXPECT_EQ(x.mode, y.mode) << "node " << i;
    EXPECT_EQ(x.feature_point, y.feature_point) << "node " << i;
    EXPECT_EQ(x.element, y.element) << "node " << i;
    EXPECT_TRUE(same_bits(x.t, y.t)) << "node " << i;
    EXPECT_TRUE(same_bits(x.coords, y.coords)) << "node " << i;
    EXPECT_EQ(x.ref_count, y.ref_count) << "node " << i;
    if (x.mode != NodeEncodingMode::kNToOne) continue;
    EXPECT_EQ(x.first_ref, y.first_ref) << "node " << i;
    for (std::uint32_t k = 0; k < x.ref_count; ++k) {
      const NodeRef &r = a.encodings.refs[x.first_ref + k], &s = b.encodings.refs[y.first_ref + k];
      EXPECT_EQ(r.node, s.node);
      EXPECT_TRUE(same_bits(r.delta, s.delta));
      EXPECT_TRUE(same_bits(r.weight, s.weight));
    }
  }
  ASSERT_EQ(a.profiles.size(), b.profiles.size());
  for (std::size_t i = 0; i < a.profiles.size(); ++i) {
    const TemplateProfile &p = a.profiles[i], &q = b.profiles[i];
    EXPECT_EQ(p.halfedge, q.halfedge) << "profile " << i;
    EXPECT_EQ(p.kind, q.kind);
    EXPECT_EQ(p.shift, q.shift);
    if (p.kind == ProfileCurve::Kind::kBezier) {
      ASSERT_EQ(p.bezier.offsets.size(), q.bezier.offsets.size());
      for (std::size_t k = 0; k < p.bezier.offsets.size(); ++k)
        EXPECT_TRUE(same_bits(p.bezier.offsets[k], q.bezier.offsets[k]));
    } else {
      EXPECT_TRUE(same_bits(p.points.a, q.points.a));
      EXPECT_TRUE(same_bits(p.points.b, q.points.b));
      ASSERT_EQ(p.points.u.size(), q.points.u.size());
      ASSERT_EQ(p.points.points.size(), q.points.points.size());
      for (std::size_t k = 0; k < p.points.u.size(); ++k) {
        EXPECT_TRUE(same_bits(p.points.u[k], q.points.u[k]));
        EXPECT_TRUE(same_bits(p.points.points[k], q.points.points[k]));
      }
    }
  }
}

void expect_same_positions(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += !same_bits(a[i], b[i]);
  EXPECT_EQ(differ, 0u) << what;
}

}  // namespace

TEST(TemplateJson, ProjectTemplatesRoundTripBitExact) {
  const Fixture& f = template_fixture();
  ASSERT_EQ(f.templates.size(), 3u);
  const std::vector<Vec3d>& body_pos = f.body.model.nodes.position;
  bool saw_bezier = false, saw_points = false, saw_joint = false, saw_n_to_one = false;
  for (const ProfileTemplate& t : f.templates) {
    SCOPED_TRACE(t.name);
    const fs::path path = scratch() / (t.name + ".json");
    write_template_json(t, path);
    const ProfileTemplate r = read_template_json(path);
    ASSERT_TRUE(validate(r.model).is_ok());
    ASSERT_TRUE(validate_template(r).is_ok());
    expect_same_template(t, r);
    // Writing what was read gives the same document (a fixed point).
    EXPECT_EQ(template_to_json_string(r), template_to_json_string(t));

    for (const auto& p : t.profiles) (p.kind == ProfileCurve::Kind::kBezier ? saw_bezier : saw_points) = true;
    saw_joint |= t.model.num_joints() > 0;
    for (const auto& e : t.encodings.nodes) saw_n_to_one |= e.mode == NodeEncodingMode::kNToOne;

    // Decoding on the reference body: bit-identical node positions.
    std::vector<Vec3d> da(t.model.nodes.slots.capacity()), db(r.model.nodes.slots.capacity());
    ASSERT_TRUE(decode_nodes(t.encodings, f.body, body_pos, da).is_ok());
    ASSERT_TRUE(decode_nodes(r.encodings, f.body, body_pos, db).is_ok());
    expect_same_positions(da, db, "decoded nodes");

    // Regeneration (no collision pass): bit-identical refined garments.
    RegenParams params;
    params.collision = false;
    params.levels = 2;
    auto ga = regenerate(t, f.body, body_pos, nullptr, params);
    auto gb = regenerate(r, f.body, body_pos, nullptr, params);
    ASSERT_TRUE(ga.has_value()) << ga.status().to_string();
    ASSERT_TRUE(gb.has_value()) << gb.status().to_string();
    EXPECT_GT(ga->model.num_faces(), t.model.num_faces());
    EXPECT_EQ(diff_tables(ga->model, gb->model), "");
    expect_same_positions(ga->model.nodes.position, gb->model.nodes.position, "regenerated nodes");
  }
  // The corpus exercises every part of the format.
  EXPECT_TRUE(saw_bezier);
  EXPECT_TRUE(saw_points);
  EXPECT_TRUE(saw_joint);
  EXPECT_TRUE(saw_n_to_one);
}

TEST(TemplateJson, DocumentIsReadableAndVersioned) {
  const ProfileTemplate& t = template_fixture().templates[0];
  const std::string text = template_to_json_string(t);
  const Json doc = Json::parse(text);
  EXPECT_EQ(doc["format"], "atelier-template");
  EXPECT_EQ(doc["version"], 1);
  EXPECT_EQ(doc["name"], t.name);
  ASSERT_EQ(doc["nodes"].size(), t.model.nodes.slots.capacity());
  // Modes are written by name, positions as [x, y, z], faces as node lists.
  EXPECT_EQ(doc["nodes"][0]["encoding"]["mode"], to_string(t.encodings.nodes[0].mode));
  EXPECT_EQ(doc["nodes"][0]["position"].size(), 3u);
  EXPECT_EQ(doc["nodes"][0]["position"][0].get<double>(), t.model.nodes.position[0].x());
  std::size_t faces = 0;
  for (const auto& s : doc["surfaces"]) faces += s["faces"].size();
  EXPECT_EQ(faces, t.model.num_faces());
  // One position per line: the pretty printer keeps number arrays inline.
  EXPECT_NE(text.find("\"position\": ["), std::string::npos);
}

TEST(TemplateJson, TombstonesAreCompactedWithTheirReferences) {
  // A template whose model lost a node and an edge: the file holds the
  // compacted model and the encodings/profiles follow their elements.
  const ProfileTemplate& orig = template_fixture().templates[1];
  ProfileTemplate t = orig;
  const std::size_t n0 = t.model.nodes.slots.capacity();
  const SurfaceIdx s = t.model.nodes.surface[0];
  const NodeIdx a = t.model.new_node(s, Vec3d(0, 0, 0));
  const NodeIdx b = t.model.new_node(s, Vec3d(1, 0, 0));
  const EdgeIdx e = t.model.new_edge(a, b);
  t.model.delete_edge(e);
  t.model.delete_node(a);
  // b stays, encoded on node 0; a's slot is a tombstone in the middle.
  t.node_names.push_back("a");
  t.node_names.push_back("b");
  t.encodings.nodes.push_back(encode_one_to_one(0, t.model.position(NodeIdx{0}), Vec3d(0, 0, 0)));
  t.encodings.nodes.push_back(encode_one_to_one(0, t.model.position(NodeIdx{0}), Vec3d(1, 0, 0)));
  if (!t.encoded_clearance.empty()) t.encoded_clearance.resize(n0 + 2, 0.5);
  t.model.complex_holes = orig.model.complex_holes;
  ASSERT_TRUE(validate_template(t).is_ok()) << validate_template(t).to_string();
  const ProfileTemplate r = template_from_json_string(template_to_json_string(t), "<tombstones>");
  ASSERT_EQ(r.model.nodes.slots.capacity(), n0 + 1);
  EXPECT_EQ(r.node_names.back(), "b");
  EXPECT_EQ(r.model.position(NodeIdx{static_cast<std::uint32_t>(n0)}), Vec3d(1, 0, 0));
  Model c = t.model;
  (void)c.compact();
  EXPECT_EQ(diff_tables(c, r.model), "");
  ASSERT_EQ(r.profiles.size(), orig.profiles.size());
  for (std::size_t i = 0; i < r.profiles.size(); ++i) EXPECT_EQ(r.profiles[i].halfedge, orig.profiles[i].halfedge);
}

namespace {

struct BrokenCase {
  std::string label;
  std::function<void(std::string&)> edit;  // edits the valid document text
  std::vector<std::string> expect;         // substrings of the error message
};

/// Applies an edit to the parsed document and prints it back.
std::function<void(std::string&)> on_json(std::function<void(Json&)> f) {
  return [f](std::string& text) {
    Json j = Json::parse(text);
    const Json before = j;
    f(j);
    if (j != before) text = j.dump(1);  // an edit that changes nothing leaves the text as it was
  };
}

}  // namespace

TEST(TemplateJson, MalformedFilesAreRefusedWithPreciseMessages) {
  // The trousers have joints and n-to-one nodes, the top point-list profiles,
  // the skirt Bezier profiles: pick each broken variant from a template that
  // has the part being broken.
  const Fixture& f = template_fixture();
  const std::string top = template_to_json_string(f.templates[0]);
  const std::string skirt = template_to_json_string(f.templates[1]);
  const std::string trousers = template_to_json_string(f.templates[2]);

  const Json tj = Json::parse(trousers);
  // A face of surface 1 of the trousers, and a joint with two members.
  ASSERT_GE(tj["surfaces"].size(), 2u);
  ASSERT_GE(tj["surfaces"][1]["faces"].size(), 4u);
  ASSERT_GE(tj["joints"].size(), 1u);
  const std::size_t n_nodes = tj["nodes"].size();
  const Json sj = Json::parse(skirt);
  ASSERT_GE(sj["profiles"].size(), 2u);
  // The template with an n-to-one node.
  const std::string* with_n_to_one = nullptr;
  for (const std::string* x : {&top, &skirt, &trousers})
    if (x->find("\"n_to_one\"") != std::string::npos) with_n_to_one = x;
  ASSERT_NE(with_n_to_one, nullptr);

  std::vector<std::pair<const std::string*, BrokenCase>> cases = {
      {&trousers,
       {"missing field",
        on_json([](Json& j) { j["nodes"][3].erase("position"); }),
        {"/nodes/3", "missing field 'position'"}}},
      {&trousers,
       {"wrong type",
        on_json([](Json& j) { j["clearance"] = "thick"; }),
        {"/clearance", "expected a number", "found a string"}}},
      {&trousers,
       {"bad mode name",
        on_json([](Json& j) { j["nodes"][5]["encoding"]["mode"] = "sideways"; }),
        {"/nodes/5/encoding/mode", "unknown encoding mode 'sideways'"}}},
      {&trousers,
       {"face node out of range",
        on_json([n_nodes](Json& j) { j["surfaces"][1]["faces"][3][0] = n_nodes + 7; }),
        {"/surfaces/1/faces/3/0", "node index " + std::to_string(n_nodes + 7) + " out of range"}}},
      {&trousers,
       {"non-finite number",
        [](std::string& text) {
          const auto p = text.find("\"clearance\": ");
          const auto q = text.find(',', p);
          text.replace(p, q - p, "\"clearance\": 1e999");
        },
        {"at byte ", "non-finite number", "1e999"}}},
      {&skirt,
       {"duplicated profile edge",
        on_json([](Json& j) { j["profiles"][1]["halfedge"] = j["profiles"][0]["halfedge"]; }),
        {"/profiles/1/halfedge", "duplicated profile edge", "already has profile 0"}}},
      {&trousers,
       {"joint members of different length",
        on_json([](Json& j) {
          // Shorten the chain of the second member of joint 0 by one node.
          const auto me = j["joints"][0]["members"][1]["mesh_edge"].get<std::size_t>();
          j["mesh_edges"][me]["nodes"].erase(j["mesh_edges"][me]["nodes"].size() - 1);
        }),
        {"/joints/0/members/1", "joint members of different length"}}},
      {&trousers,
       {"truncated file",
        [](std::string& text) { text.resize(text.size() * 2 / 3); },
        {"truncated file", "invalid JSON"}}},
      {&trousers, {"wrong version", on_json([](Json& j) { j["version"] = 2; }), {"/version", "unsupported version 2"}}},
      {&trousers,
       {"non-manifold face list",
        on_json([](Json& j) {
          // The same face twice: each of its halfedges would bound two faces.
          auto& faces = j["surfaces"][1]["faces"];
          faces.push_back(faces[2]);
        }),
        {"/surfaces/1/faces/", "non-manifold face list", "already bounds face"}}},
      {&trousers,
       {"wrong format", on_json([](Json& j) { j["format"] = "obj"; }), {"/format", "not an atelier template"}}},
      {&trousers,
       {"negative index", on_json([](Json& j) { j["nodes"][2]["surface"] = -1; }), {"/nodes/2/surface", "negative"}}},
      {&trousers,
       {"position of two numbers",
        on_json([](Json& j) { j["nodes"][4]["position"].erase(2); }),
        {"/nodes/4/position", "expected 3 numbers"}}},
      {&top,
       {"profile parameter outside (0, 1)",
        on_json([](Json& j) {
          for (auto& p : j["profiles"])
            if (p["kind"] == "points") {
              p["u"][0] = 1.5;
              return;
            }
        }),
        {"/u/0", "outside (0, 1)"}}},
      {&trousers,
       {"edge joins a node to itself",
        on_json([](Json& j) { j["edges"][6][1] = j["edges"][6][0]; }),
        {"/edges/6", "to itself"}}},
      {with_n_to_one,
       {"bad n-to-one reference",
        on_json([](Json& j) {
          for (auto& n : j["nodes"])
            if (n["encoding"]["mode"] == "n_to_one") {
              n["encoding"]["refs"][0]["node"] = j["nodes"].size();
              return;
            }
        }),
        {"/encoding/refs/0/node", "out of range"}}},
      {&trousers, {"not an object", [](std::string& text) { text = "[1, 2, 3]"; }, {"expected an object"}}},
      {&trousers, {"empty file", [](std::string& text) { text.clear(); }, {"invalid JSON"}}},
      {&skirt,
       {"unknown profile kind",
        on_json([](Json& j) { j["profiles"][0]["kind"] = "spline"; }),
        {"/profiles/0/kind", "unknown profile kind 'spline'"}}},
      {&trousers,
       {"missing edge of a face", on_json([](Json& j) { j["edges"].erase(j["edges"].size() - 1); }), {"no edge"}}},
  };
  ASSERT_GE(cases.size(), 12u);

  const fs::path dir = scratch();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const BrokenCase& c = cases[i].second;
    SCOPED_TRACE(c.label);
    std::string text = *cases[i].first;
    c.edit(text);
    ASSERT_NE(text, *cases[i].first) << "the edit changed nothing";
    const fs::path path = dir / ("broken_" + std::to_string(i) + ".json");
    {
      std::ofstream out(path, std::ios::binary);
      out << text;
    }
    try {
      (void)read_template_json(path);
      ADD_FAILURE() << "no error for: " << c.label;
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << msg;
      EXPECT_NE(msg.find(path.string()), std::string::npos) << msg;
      for (const std::string& s : c.expect)
        EXPECT_NE(msg.find(s), std::string::npos) << "'" << s << "' not in: " << msg;
    }
  }
}

TEST(TemplateJson, EveryTruncationIsAParseError) {
  // Never a crash, whatever prefix of a valid file is read.
  const std::string text = template_to_json_string(template_fixture().templates[2]);
  std::size_t step = text.size() / 97 + 1;
  for (std::size_t n = 0; n < text.size() - 2; n += step) {
    try {
      (void)template_from_json_string(std::string_view(text).substr(0, n), "<prefix>");
      ADD_FAILURE() << "prefix of " << n << " bytes accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse);
      EXPECT_NE(std::string(e.what()).find("<prefix>"), std::string::npos);
    }
  }
}

TEST(TemplateJson, UnwritablePathLeavesNothingBehind) {
  const ProfileTemplate& t = template_fixture().templates[1];
  const fs::path dir = scratch() / "unwritable";
  fs::create_directories(dir);
  // A missing directory: Error naming the file, nothing created.
  const fs::path missing = dir / "no_such_dir" / "t.json";
  try {
    write_template_json(t, missing);
    ADD_FAILURE() << "wrote into a missing directory";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.json"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(missing));
  EXPECT_FALSE(fs::exists(missing.parent_path()));

  // An invalid template: Error, the previous file at the path is untouched
  // and no temporary is left next to it.
  const fs::path good = dir / "keep.json";
  write_template_json(t, good);
  const std::string before = template_to_json_string(t);
  ProfileTemplate bad = t;
  bad.node_names.pop_back();  // one name short: does not validate
  EXPECT_THROW(write_template_json(bad, good), Error);
  ProfileTemplate nan = t;
  nan.clearance = std::nan("");
  EXPECT_THROW(write_template_json(nan, good), Error);
  std::ifstream in(good, std::ios::binary);
  const std::string after((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(after, before);
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST(TemplateJson, DocumentationExampleReads) {
  // The example in docs/template-format.md is a valid file.
  const fs::path doc = fs::path(ATELIER_TEST_DATA).parent_path().parent_path() / "docs" / "template-format.md";
  std::ifstream in(doc, std::ios::binary);
  ASSERT_TRUE(in) << doc;
  const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto a = md.find("```json\n");
  ASSERT_NE(a, std::string::npos);
  const auto b = md.find("```", a + 8);
  ASSERT_NE(b, std::string::npos);
  const ProfileTemplate t = template_from_json_string(std::string_view(md).substr(a + 8, b - a - 8), "docs example");
  EXPECT_EQ(t.name, "patch");
  EXPECT_EQ(t.model.num_nodes(), 4u);
  EXPECT_EQ(t.model.num_edges(), 4u);
  EXPECT_EQ(t.model.num_faces(), 1u);
  ASSERT_EQ(t.profiles.size(), 1u);
  EXPECT_EQ(t.model.tail(t.profiles[0].halfedge), NodeIdx{0});
  EXPECT_EQ(t.model.head(t.profiles[0].halfedge), NodeIdx{1});
  EXPECT_EQ(t.encodings.nodes[3].mode, NodeEncodingMode::kNToOne);
  EXPECT_EQ(t.encodings.nodes[3].ref_count, 2u);
  EXPECT_TRUE(validate(t.model).is_ok());
}

namespace {

/// JSON pointers of every integer leaf of a document.
void integer_leaves(const Json& j, const std::string& ptr, std::vector<std::string>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) integer_leaves(it.value(), ptr + "/" + it.key(), out);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) integer_leaves(j[i], ptr + "/" + std::to_string(i), out);
  } else if (j.is_number_integer()) {
    out.push_back(ptr);
  }
}

}  // namespace

TEST(TemplateJson, EveryIndexChangeIsReadOrRefusedNeverACrash) {
  // Every integer of the trousers file (node, edge, face, surface, mesh edge
  // and attribute indices, flags, counts) set to its neighbour value, to 0
  // and to a huge value: the reader either gives a template that validates
  // or throws Error(kParse) naming the file; it never crashes or hangs.
  const std::string text = template_to_json_string(template_fixture().templates[2]);
  const Json doc = Json::parse(text);
  std::vector<std::string> leaves;
  integer_leaves(doc, "", leaves);
  ASSERT_GT(leaves.size(), 500u);
  std::size_t accepted = 0, refused = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const Json::json_pointer ptr(leaves[i]);
    const std::int64_t v = doc[ptr].get<std::int64_t>();
    for (const std::int64_t w : {v + 1, std::int64_t{0}, std::int64_t{1} << 40}) {
      if (w == v) continue;
      Json j = doc;
      j[ptr] = w;
      try {
        const ProfileTemplate t = template_from_json_string(j.dump(), "<mutant>");
        EXPECT_TRUE(validate_template(t).is_ok()) << leaves[i] << " = " << w;
        ++accepted;
      } catch (const Error& e) {
        EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
        EXPECT_NE(std::string(e.what()).find("<mutant>"), std::string::npos) << e.what();
        ++refused;
      }
    }
  }
  // Most changes break the model; some (an encoding's body element, a feature point
  // id, the refinement levels) are legal.
  EXPECT_GT(refused, accepted);
  EXPECT_GT(accepted, 0u);
}

TEST(TemplateJson, NumbersAndLevelsBeyondWhatRegenerationTakesAreRefusedWhenRead) {
  // Issue 27: a coordinate of 1e300 was accepted (a body then took minutes,
  // the point becoming inf as a float in the BVH query), and levels up to 16
  // although regeneration refuses more than 8 (every body failed, exit 1).
  const std::string top = template_to_json_string(template_fixture().templates[0]);
  const Json doc = Json::parse(top);
  auto refused = [&](const std::function<void(Json&)>& edit, const std::vector<std::string>& fragments) {
    Json j = doc;
    edit(j);
    try {
      (void)template_from_json_string(j.dump(), "edited.template.json");
      ADD_FAILURE() << "accepted: " << fragments.front();
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse);
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  };
  refused([](Json& j) { j["nodes"][2]["position"][0] = 1e300; },
          {"edited.template.json", "/nodes/2/position/0", "out of range"});
  refused([](Json& j) { j["nodes"][1]["encoding"]["coords"][1] = -2e4; },
          {"/nodes/1/encoding/coords/1", "out of range"});
  refused([](Json& j) { j["clearance"] = 1e5; }, {"/clearance", "out of range"});
  refused([](Json& j) { j["levels"] = kMaxTemplateLevels + 1; }, {"/levels", "out of range [0, 8]"});
  // The largest accepted values do read, and the largest level regenerates
  // (the check and regeneration agree on the bound).
  Json ok = doc;
  ok["levels"] = kMaxTemplateLevels;
  EXPECT_EQ(template_from_json_string(ok.dump(), "ok.json").levels, kMaxTemplateLevels);
  ProfileTemplate t = template_fixture().templates[0];
  t.levels = kMaxTemplateLevels + 1;
  EXPECT_FALSE(validate_template(t).is_ok());
}

TEST(TemplateJson, ReferencesOutOfTheBodyAreFoundWhenTheTemplateIsRead) {
  // Issue 27: a feature point id or body element out of range was found per
  // body (every body failing, the message not naming the file).
  const Fixture& f = template_fixture();
  const std::string top = template_to_json_string(f.templates[0]);
  const fs::path dir = scratch();
  // The template as written reads against its body.
  {
    std::ofstream(dir / "good.template.json") << top;
    EXPECT_NO_THROW((void)read_template_json(dir / "good.template.json", f.body));
  }
  Json doc = Json::parse(top);
  // One node of each body-referring kind present in the template.
  std::map<std::string, std::size_t> node_of_mode;
  for (std::size_t i = 0; i < doc["nodes"].size(); ++i)
    node_of_mode.try_emplace(doc["nodes"][i]["encoding"]["mode"].get<std::string>(), i);
  ASSERT_TRUE(node_of_mode.count("feature_point") || node_of_mode.count("feature_offset"));
  std::size_t broken_cases = 0;
  for (const auto& [mode, i] : node_of_mode) {
    Json j = doc;
    const bool feature = mode == "feature_point" || mode == "feature_offset";
    if (feature) {
      j["nodes"][i]["encoding"]["feature_point"] = 100000;
    } else if (mode == "vertex" || mode == "edge" || mode == "face") {
      j["nodes"][i]["encoding"]["element"] = 50000000;
    } else {
      continue;
    }
    ++broken_cases;
    const fs::path p = dir / ("broken-" + mode + ".template.json");
    std::ofstream(p) << j.dump();
    EXPECT_NO_THROW((void)read_template_json(p));  // without the body it cannot be told
    try {
      (void)read_template_json(p, f.body);
      ADD_FAILURE() << mode << ": accepted";
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_EQ(e.status().code(), ErrorCode::kParse);
      EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find("node " + std::to_string(i)), std::string::npos) << msg;
      EXPECT_NE(msg.find(feature ? "feature point 100000" : "50000000"), std::string::npos) << msg;
    }
  }
  EXPECT_GE(broken_cases, 1u);
}
