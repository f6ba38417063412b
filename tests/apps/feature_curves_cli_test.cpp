// `atelier encode --reference BODY.obj --features CURVES.json` and `atelier
// regen --source DIR --reference BODY.obj --features CURVES.json` (issue 26,
// "any reference body"): mannequin bodies written by `atelier bodies`,
// rewritten in centimetres and Z-up with the reference's curves as JSON in
// that frame, give the skirt of the same files in metres and Y-up, written
// back in centimetres and Z-up; bad curve files and a missing --features
// are explained and leave no output.
#include <atelier/systems/body/body_file.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/feature_curve_files.h"
#include "support/run_command.h"

namespace fs = std::filesystem;
using namespace atelier;

namespace {

using atelier::testing::read_bytes;
using atelier::testing::run_cli;
using atelier::testing::scratch_dir;

std::vector<Vec3d> vertices(const fs::path& obj) {
  std::istringstream text(read_bytes(obj));
  std::vector<Vec3d> v;
  for (std::string l; std::getline(text, l);)
    if (l.rfind("v ", 0) == 0) {
      std::istringstream s(l.substr(2));
      Vec3d p;
      s >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    }
  return v;
}

void write_text(const fs::path& p, const std::string& s) {
  std::ofstream(p) << s;
}

}  // namespace

TEST(FeatureCurvesCli, ASkirtOnAFamilyInCentimetresZUpIsTheSkirtInMetresYUp) {
  const fs::path d = scratch_dir("feature_curves_cli");
  auto r = run_cli("--seed 5 bodies --count 3 --meshes 3 --out " + (d / "bodies").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<fs::path> objs;
  for (const auto& e : fs::directory_iterator(d / "bodies"))
    if (e.path().extension() == ".obj") objs.push_back(e.path());
  std::sort(objs.begin(), objs.end());
  ASSERT_EQ(objs.size(), 3u);
  // The reference: the first body, read as OBJ (mannequin topology: it takes
  // the engine's curves, which the JSON files then hold).
  auto ref = read_reference_body(objs[0]);
  ASSERT_TRUE(ref) << ref.status().message();
  ASSERT_FALSE(ref->curves.empty());
  for (const std::string frame : {"m", "cm"}) {
    const auto map = frame == "cm" ? &atelier::testing::to_cm_z_up : &atelier::testing::same_frame;
    fs::create_directories(d / frame / "set");
    for (const fs::path& o : objs) {
      auto b = read_reference_body(o);
      ASSERT_TRUE(b);
      atelier::testing::write_body_obj(*b, d / frame / "set" / o.filename(), map);
    }
    atelier::testing::write_body_obj(*ref, d / frame / "ref.obj", map);
    atelier::testing::write_body_curves(*ref, d / frame / "curves.json", map, frame == "cm" ? "cm" : "",
                                        frame == "cm" ? "z" : "");
  }
  const std::string cm = " --scale 0.01 --up z";
  for (const std::string frame : {"m", "cm"}) {
    const std::string opts = (frame == "cm" ? cm : "") + " --features " + (d / frame / "curves.json").string();
    r = run_cli("encode --template skirt --reference " + (d / frame / "ref.obj").string() + opts + " --out " +
                (d / frame / "tpl").string());
    ASSERT_EQ(r.code, 0) << r.out;
    ASSERT_TRUE(fs::exists(d / frame / "tpl" / "skirt.template.json")) << r.out;
    r = run_cli("regen --template " + (d / frame / "tpl" / "skirt.template.json").string() + " --source " +
                (d / frame / "set").string() + " --reference " + (d / frame / "ref.obj").string() + opts +
                " --meshes 3 --out " + (d / frame / "run").string());
    ASSERT_EQ(r.code, 0) << r.out;
  }
  const auto rep_m = nlohmann::json::parse(read_bytes(d / "m" / "run" / "report.json"));
  const auto rep_c = nlohmann::json::parse(read_bytes(d / "cm" / "run" / "report.json"));
  ASSERT_EQ(rep_m["summary"]["completed"], 3) << rep_m.dump();
  ASSERT_EQ(rep_c["summary"]["completed"], 3) << rep_c.dump();
  std::vector<Vec3d> first;
  for (const fs::path& o : objs) {
    const std::string body = o.stem().string();
    const auto gm = vertices(d / "m" / "run" / "bodies" / body / "skirt.obj");
    const auto gc = vertices(d / "cm" / "run" / "bodies" / body / "skirt.obj");
    ASSERT_EQ(gm.size(), gc.size());
    ASSERT_GT(gm.size(), 100u);
    // In the files' frame: the metres/Y-up skirt mapped, to 1e-6 of the
    // body's size (2 m; the meshes are written in float precision).
    double worst = 0;
    for (std::size_t v = 0; v < gm.size(); ++v)
      worst = std::max(worst, (gc[v] - atelier::testing::to_cm_z_up(gm[v])).cwiseAbs().maxCoeff() / 200.0);
    EXPECT_LE(worst, 1e-6) << body;
    if (first.empty()) {
      first = gm;
    } else {
      double moved = 0;
      for (std::size_t v = 0; v < gm.size(); ++v) moved = std::max(moved, (gm[v] - first[v]).norm());
      EXPECT_GT(moved, 1e-3) << body << ": the skirt followed the body";
    }
  }
  for (std::size_t b = 0; b < 3; ++b) EXPECT_EQ(rep_m["bodies"][b]["templates"]["skirt"]["inside_nodes"], 0);

  // ---- errors: each named, exit 3, no output folder left behind.
  const std::string ref_cm = " --reference " + (d / "cm" / "ref.obj").string() + cm;
  auto refused = [&](const std::string& args, const std::string& out, std::initializer_list<std::string> says) {
    const auto e = run_cli(args + " --out " + (d / out).string());
    EXPECT_EQ(e.code, 3) << args << "\n" << e.out;
    for (const auto& s : says) EXPECT_NE(e.out.find(s), std::string::npos) << "'" << s << "' not in: " << e.out;
    EXPECT_FALSE(fs::exists(d / out)) << out << " was left behind";
  };
  // No --features on a body of an unknown topology (a closed tetrahedron;
  // the mannequin's topology would bring its own curves): only detail
  // templates apply, and --features is named.
  fs::create_directories(d / "tet_set");
  write_text(d / "tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  fs::copy_file(d / "tet.obj", d / "tet_set" / "a.obj");
  refused("encode --template skirt --reference " + (d / "tet.obj").string(), "e_none",
          {"only detail templates apply", "--features"});
  refused("regen --template " + (d / "cm" / "tpl" / "skirt.template.json").string() + " --source " +
              (d / "tet_set").string() + " --reference " + (d / "tet.obj").string(),
          "e_regen_none", {"only detail templates", "--features"});
  // A template encoded on the file's curves, regenerated without them (the
  // reference, of the mannequin's topology, would bring the mannequin's own
  // curves and feature points, other ids) or with other curves: refused.
  refused("regen --template " + (d / "cm" / "tpl" / "skirt.template.json").string() + " --source " +
              (d / "cm" / "set").string() + ref_cm,
          "e_regen_own", {"feature curves from a file", "give the same --features file"});
  {
    auto fewer = read_feature_curves(d / "cm" / "curves.json");
    ASSERT_TRUE(fewer);
    fewer->curves.pop_back();  // a curve that the skirt does not use, gone
    atelier::testing::write_curves_json(*fewer, d / "fewer.json");
  }
  refused("regen --template " + (d / "cm" / "tpl" / "skirt.template.json").string() + " --source " +
              (d / "cm" / "set").string() + ref_cm + " --features " + (d / "fewer.json").string(),
          "e_regen_other", {"gives other curves"});
  // Malformed JSON: the line is named.
  write_text(d / "bad.json", "{\"curves\": [\n{\"name\": \"waist\",\n \"closed\": tru}]}");
  refused("encode --template skirt" + ref_cm + " --features " + (d / "bad.json").string(), "e_bad", {"bad.json:3:"});
  // An unknown curve name.
  write_text(d / "name.json",
             "{\"curves\": [{\"name\": \"belly\", \"closed\": true, \"points\": [[0,0,0],[1,0,0],[0,1,0]]}]}");
  refused("encode --template skirt" + ref_cm + " --features " + (d / "name.json").string(), "e_name",
          {"name.json:1:", "unknown curve name \"belly\""});
  // A point far from the surface (the body's own curves, one point 20 cm out).
  auto file = read_feature_curves(d / "cm" / "curves.json");
  ASSERT_TRUE(file);
  file->curves[0].points[2] *= 1.5;
  atelier::testing::write_curves_json(*file, d / "far.json");
  refused("encode --template skirt" + ref_cm + " --features " + (d / "far.json").string(), "e_far",
          {"far.json:7: curve '" + file->curves[0].name + "', point 2 is", "from the body's surface"});
}
