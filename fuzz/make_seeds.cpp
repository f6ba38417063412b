// Writes the generated fuzz seeds into <out>/<harness>/: the binary formats
// (.atm, .atd) and template JSON from small models built here, and small
// text files that exercise each reader's statements (the files of tests/data
// are added by scripts/fuzz.sh). Usage: make_seeds <out-dir>
#include <filesystem>
#include <fstream>
#include <string>

#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/profile/template_json.h>

namespace fs = std::filesystem;
using namespace atelier;

namespace {

void put(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << bytes;
}

const char* kCube =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "g box\nf 1/1 4/2 3/3 2/4\nf 5/1 6/2 7/3 8/4\nf 1/1 2/2 6/3 5/4\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
const char* kTwoGroups = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng a\nf 1 2 3\ng b\nf 1 3 4\n";
const char* kFin =  // three faces on one edge, in three groups
    "v 0 0 0\nv 0 0 1\nv 1 0 0\nv -1 0 0\nv 0 1 0\ng a\nf 1 2 3\ng b\nf 2 1 4\ng c\nf 1 2 5\n";

ProfileTemplate tiny_template() {
  ProfileTemplate t;
  t.name = "tiny";
  t.reference = "none";
  t.model = read_obj_from_string("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\ng panel\nf 1 2 3\nf 2 4 3\n");
  const std::size_t n = t.model.nodes.slots.capacity();
  t.node_names = {"a", "b", "c", "d"};
  t.node_names.resize(n);
  t.encodings.nodes.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    NodeEncoding& e = t.encodings.nodes[i];
    e.mode = i == 3 ? NodeEncodingMode::kOneToOne : NodeEncodingMode::kVertex;
    e.element = i == 3 ? 0u : static_cast<std::uint32_t>(i);
    e.coords = Vec3d(0.01 * static_cast<double>(i), 0.0, 0.02);
  }
  t.model.nodes.props.remove("source_vertex");
  TemplateProfile p;
  p.halfedge = t.model.faces.halfedge[0];
  p.bezier.offsets = {Vec3d(0, 0, 0), Vec3d(0.1, 0.2, 0.0), Vec3d(0, 0, 0)};
  t.profiles.push_back(p);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const fs::path out = argv[1];
  // Text formats.
  put(out / "obj", "cube_vt.obj", kCube);
  put(out / "obj", "two_groups.obj", kTwoGroups);
  put(out / "obj", "fin.obj", kFin);
  put(out / "obj", "bom_relative.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0 \\\n\nv 0 1 0 1\nvn 0 0 1\nf -3//1 -2//1 -1//1\n");
  put(out / "off", "tri.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  put(out / "ply", "tri_uv.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float u\n"
      "property float v\nelement face 1\nproperty list uchar int vertex_indices\nproperty int surface\nend_header\n"
      "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2 0\n");
  put(out / "mhclo", "small.mhclo",
      "# a garment\nname shirt\nobj_file shirt.obj\nz_depth 50\nx_scale 1 2 1.5\ny_scale 3 4 2.0\nz_scale 5 6 0.5\n"
      "verts 0\n1 2 3 0.2 0.3 0.5 0.01 -0.02 0.03\n  \n7\n4 5 6 1 0 0 0 0 0\ndelete_verts\n1 2 - 9 12\n");
  put(out / "mh_target", "small.target", "# target\n0 0.1 0.2 0.3\n17 -1e-3 2.5e-2 0\n19999 1 1 1\n");
  put(out / "mh_base", "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\ng body\nf 1/1 2/1 3/1 4/1\ng helper\nf -4 -2 -1\n");
  put(out / "mh_modifiers", "modifiers.json",
      std::string("\x01") + R"([{"group": "measure", "modifiers": [{"target": "measure-waist-circ", "min": "decr", "max": "incr"}, {"target": "x"}]}])");
  put(out / "mh_modifiers", "measures.json", std::string("\x00", 1) + R"({"measures": {"waist": [1, 2, 3], "neck": [4]}})");
  put(out / "feature_curves", "curves.json",
      "{\"units\": \"cm\", \"up\": \"z\", \"curves\": [\n"
      "  {\"name\": \"waist\", \"closed\": true, \"points\": [[10, 0, 100], [0, 8, 100.5], [-10, 0, 1e2], [0, -8, "
      "99.75], [10, 0, 100]]},\n"
      "  {\"name\": \"centre_front\", \"closed\": false, \"points\": [[0, -8, 120], [0, -8.5, 80.25E0]]}]}\n");
  put(out / "feature_curves", "escapes.json",
      "\xEF\xBB\xBF{\"curves\": [{\"name\": \"hip\", \"points\": [[0,0,0],[1,0,0],[0,1,0]], \"closed\": true}], "
      "\"up\": \"y\", \"units\": \"mm\"}");
  // Binary formats from models built here.
  put(out / "atm", "cube.atm", serialize_model(read_obj_from_string(kCube)));
  put(out / "atm", "two_groups.atm", serialize_model(read_obj_from_string(kTwoGroups)));
  put(out / "atm", "empty.atm", serialize_model(Model{}));
  DetailEncoding d;
  d.polygon_count = 2;
  d.body_node_count = 4;
  d.topology_hash = 0x1234;
  d.row = {0, 1, 3, 4};
  d.polygon = {0, 1, 0, 1};
  d.a = {0.1f, 0.2f, 0.3f, 0.4f};
  d.b = d.a;
  d.c = d.a;
  d.d = d.a;
  fs::create_directories(out / "atd");
  write_detail(d, out / "atd" / "small.atd");
  d.reference_corners = {{0.f, 0.f}, {1.f, 0.f}, {0.f, 1.f}, {1.f, 1.f}, {0.f, 0.f}, {1.f, 1.f}};
  write_detail(d, out / "atd" / "corners.atd");
  put(out / "template", "tiny.json", template_to_json_string(tiny_template()));
  return 0;
}
