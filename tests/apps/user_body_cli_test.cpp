// `atelier encode --reference BODY.obj --scale S --up z` and `atelier regen
// --source DIR --reference BODY.obj --scale S --up z` (issue 26, "any
// reference body"): mannequin bodies written by `atelier bodies`, rewritten
// in centimetres and Z-up, give the results of the bodies in metres and
// Y-up, written back in centimetres and Z-up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::run_cli;
using atelier::testing::scratch_dir;

using P = std::array<double, 3>;

/// Copies an OBJ file, each `v` line mapped by `map` and written exactly.
template <class Map>
void rewrite_obj(const fs::path& in, const fs::path& out, Map map) {
  std::istringstream text(read_bytes(in));
  std::ofstream o(out);
  char buf[128];
  for (std::string l; std::getline(text, l);) {
    if (l.rfind("v ", 0) == 0) {
      std::istringstream s(l.substr(2));
      P p{};
      s >> p[0] >> p[1] >> p[2];
      const P q = map(p);
      std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g", q[0], q[1], q[2]);
      o << buf << '\n';
    } else {
      o << l << '\n';
    }
  }
}

std::vector<P> obj_vertices(const fs::path& obj) {
  std::istringstream text(read_bytes(obj));
  std::vector<P> v;
  for (std::string l; std::getline(text, l);)
    if (l.rfind("v ", 0) == 0) {
      std::istringstream s(l.substr(2));
      P p{};
      s >> p[0] >> p[1] >> p[2];
      v.push_back(p);
    }
  return v;
}

// Metres, Y-up (X, Y, Z) is centimetres, Z-up (X, -Z, Y).
P to_cm_z(const P& p) {
  return {100 * p[0], -100 * p[2], 100 * p[1]};
}
P identity(const P& p) {
  return p;
}
/// Garment files are read in float precision: on a grid of 2^-16 m, a
/// coordinate and 100 times it are both floats, so both frames give the
/// engine the same bits.
P grid(const P& p) {
  P q;
  for (int k = 0; k < 3; ++k) q[k] = std::round(p[k] * 65536) / 65536;
  return q;
}

}  // namespace

TEST(UserBodyCli, AMannequinFamilyInCentimetresZUpEncodesAndRegeneratesAsInMetresYUp) {
  const fs::path d = scratch_dir("user_body_cli");
  auto r = run_cli("--seed 3 bodies --count 2 --meshes 2 --out " + (d / "bodies").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<fs::path> objs;
  for (const auto& e : fs::directory_iterator(d / "bodies"))
    if (e.path().extension() == ".obj") objs.push_back(e.path());
  std::sort(objs.begin(), objs.end());
  ASSERT_EQ(objs.size(), 2u);
  const fs::path garment = encoded_templates() / "top.obj";  // a garment on the mannequin
  for (const auto& [frame, map] : {std::pair{"m", &identity}, std::pair{"cm", &to_cm_z}}) {
    fs::create_directories(d / frame / "set");
    for (const fs::path& o : objs) rewrite_obj(o, d / frame / "set" / o.filename(), map);
    rewrite_obj(objs[0], d / frame / "ref.obj", map);
    // (a copy: clang 14 cannot capture a structured binding)
    rewrite_obj(garment, d / frame / "top.obj", [&, to = map](const P& p) { return to(grid(p)); });
  }
  const std::string cm = " --scale 0.01 --up z";
  for (const std::string frame : {"m", "cm"}) {
    const std::string opts = frame == "cm" ? cm : "";
    r = run_cli("encode --garment " + (d / frame / "top.obj").string() + " --reference " +
                (d / frame / "ref.obj").string() + opts + " --out " + (d / frame / "tpl").string());
    ASSERT_EQ(r.code, 0) << r.out;
    ASSERT_TRUE(fs::exists(d / frame / "tpl" / "top.atd")) << r.out;
    r = run_cli("regen --template " + (d / frame / "tpl" / "top.atd").string() + " --source " +
                (d / frame / "set").string() + " --reference " + (d / frame / "ref.obj").string() + opts +
                " --meshes 2 --out " + (d / frame / "run").string());
    ASSERT_EQ(r.code, 0) << r.out;
  }
  // The template pair is in metres and Y-up whatever the files' frame: the
  // same bytes (bodies written by `bodies` are floats: 100 times them is
  // exact, and dividing by 100 gives them back).
  EXPECT_EQ(read_bytes(d / "m" / "tpl" / "top.atd"), read_bytes(d / "cm" / "tpl" / "top.atd"));
  EXPECT_EQ(read_bytes(d / "m" / "tpl" / "top.obj"), read_bytes(d / "cm" / "tpl" / "top.obj"));
  const auto tm = obj_vertices(d / "m" / "tpl" / "top.obj");
  // Each body's garment: in the files' frame, the metres/Y-up result mapped
  // (the meshes are written in float: relative 1e-6).
  const auto rep_m = nlohmann::json::parse(read_bytes(d / "m" / "run" / "report.json"));
  const auto rep_c = nlohmann::json::parse(read_bytes(d / "cm" / "run" / "report.json"));
  ASSERT_EQ(rep_m["summary"]["completed"], 2) << rep_m.dump();
  ASSERT_EQ(rep_c["summary"]["completed"], 2) << rep_c.dump();
  for (const fs::path& o : objs) {
    const std::string body = o.stem().string();
    const auto gm = obj_vertices(d / "m" / "run" / "bodies" / body / "top.obj");
    const auto gc = obj_vertices(d / "cm" / "run" / "bodies" / body / "top.obj");
    ASSERT_EQ(gm.size(), gc.size());
    ASSERT_GT(gm.size(), 10u);
    double worst = 0, moved = 0;
    for (std::size_t v = 0; v < gm.size(); ++v) {
      const P want = to_cm_z(gm[v]);
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(gc[v][k] - want[k]) / 200.0);  // body ~2 m
      for (int k = 0; k < 3; ++k) moved = std::max(moved, std::abs(gm[v][k] - tm[v][k]));
    }
    EXPECT_LE(worst, 1e-6) << body;
    if (body != objs[0].stem().string()) {
      EXPECT_GT(moved, 1e-3) << body << ": the garment followed the body";
    }
  }
  for (std::size_t b = 0; b < 2; ++b) {
    const auto& qm = rep_m["bodies"][b]["templates"]["top"];
    EXPECT_EQ(qm["inside_nodes"], 0);
    // The engine saw the same bits: the same figures, to the last digit.
    EXPECT_EQ(rep_c["bodies"][b]["templates"], rep_m["bodies"][b]["templates"]);
  }
}

TEST(UserBodyCli, OpenBodiesWrongTopologyMembersAndProfileTemplatesAreExplained) {
  const fs::path d = scratch_dir("user_body_cli_bad");
  fs::create_directories(d / "set");
  // A cube with one face missing: open.
  {
    std::ofstream f(d / "open.obj");
    f << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
         "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\n";
  }
  auto r = run_cli("encode --garment " + (encoded_templates() / "top.obj").string() + " --reference " +
                   (d / "open.obj").string() + " --out " + (d / "tpl").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("open.obj"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not closed"), std::string::npos) << r.out;
  // A closed tetrahedron reference and a family member of another topology.
  {
    std::ofstream f(d / "tet.obj");
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  fs::copy_file(d / "tet.obj", d / "set" / "a.obj");
  fs::copy_file(d / "open.obj", d / "set" / "b.obj");
  // Profile templates need feature curves: the message says only detail templates apply.
  r = run_cli("encode --template top --reference " + (d / "tet.obj").string() + " --out " + (d / "tpl").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("only detail templates apply"), std::string::npos) << r.out;
  // A garment around the tetrahedron: a bigger tetrahedron's faces.
  {
    std::ofstream f(d / "shell.obj");
    f << "v -0.1 -0.1 -0.1\nv 1.3 -0.1 -0.1\nv -0.1 1.3 -0.1\nv -0.1 -0.1 1.3\nf 1 3 2\nf 1 2 4\nf 1 4 3\n";
  }
  r = run_cli("encode --garment " + (d / "shell.obj").string() + " --reference " + (d / "tet.obj").string() +
              " --out " + (d / "tpl").string());
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cli("regen --template " + (d / "tpl" / "shell.atd").string() + " --source " + (d / "set").string() +
              " --reference " + (d / "tet.obj").string() + " --out " + (d / "run").string());
  EXPECT_EQ(r.code, 1) << r.out;  // the other members complete
  EXPECT_NE(r.out.find("b.obj"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("topology differs"), std::string::npos) << r.out;
  const auto rec = nlohmann::json::parse(read_bytes(d / "run" / "bodies" / "b.json"));
  EXPECT_EQ(rec["ok"], false);
  EXPECT_NE(rec["reason"].get<std::string>().find("b.obj"), std::string::npos) << rec.dump();
  // A body file that is not there: bad input naming it.
  r = run_cli("encode --garment " + (d / "shell.obj").string() + " --reference " + (d / "nobody.obj").string() +
              " --out " + (d / "tpl").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("nobody.obj: no such file"), std::string::npos) << r.out;
  // An up axis that is not y or z is a usage error.
  r = run_cli("encode --garment " + (d / "shell.obj").string() + " --reference " + (d / "tet.obj").string() +
              " --up x --out " + (d / "tpl").string());
  EXPECT_EQ(r.code, 2) << r.out;
}
