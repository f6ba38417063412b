// Writing a profile template as JSON (systems/profile/template_json.h):
// to_json checks that the file will read back, then writes the template
// table after table in the order the reader builds them; emit pretty-prints
// it. A template with tombstones is written compacted.
#include <atelier/systems/profile/template_json.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <atelier/io/atomic_file.h>
#include <atelier/storage/validate.h>

#include "template_json_detail.h"

namespace atelier {

namespace {

using Json = nlohmann::ordered_json;
using template_json_detail::kMaxLevels;

// ------------------------------------------------------------------ names

const char* kind_name(ProfileCurve::Kind k) noexcept {
  return k == ProfileCurve::Kind::kBezier ? "bezier" : "points";
}
const char* shift_name(ShiftMode m) noexcept {
  return m == ShiftMode::kScale ? "scale" : "scale_rotate";
}
const char* attrib_kind_name(AttribNodeKind k) noexcept {
  switch (k) {
    case AttribNodeKind::kVertex:
      return "vertex";
    case AttribNodeKind::kEdge:
      return "edge";
    case AttribNodeKind::kFace:
      return "face";
  }
  return "?";
}

// ------------------------------------------------------------------ writing

[[noreturn]] void refuse(const std::string& name, const std::string& what) {
  throw Error(Status(ErrorCode::kInvalidArgument, "template '" + name + "': cannot write: " + what));
}

Json num(double x, const std::string& tname, const char* what) {
  // JSON has no NaN or infinity; refusing here keeps files readable back.
  if (!std::isfinite(x)) refuse(tname, std::string("non-finite number in ") + what);
  return Json(x);
}
Json vec(const Vec3d& p, const std::string& tname, const char* what) {
  return Json::array({num(p.x(), tname, what), num(p.y(), tname, what), num(p.z(), tname, what)});
}

bool has_tombstones_in_any_table(const Model& m) {
  return m.nodes.slots.size() != m.nodes.slots.capacity() || m.edges.slots.size() != m.edges.slots.capacity() ||
         m.faces.slots.size() != m.faces.slots.capacity() || m.surfaces.slots.size() != m.surfaces.slots.capacity() ||
         m.mesh_edges.slots.size() != m.mesh_edges.slots.capacity() ||
         m.mesh_loops.slots.size() != m.mesh_loops.slots.capacity() ||
         m.joints.slots.size() != m.joints.slots.capacity() ||
         m.attrib_nodes.slots.size() != m.attrib_nodes.slots.capacity() ||
         m.attrib_edges.slots.size() != m.attrib_edges.slots.capacity();
}

/// compact() on a copy, with the per-node arrays, node references of the
/// encodings and profile halfedges moved along.
ProfileTemplate compacted(const ProfileTemplate& t) {
  ProfileTemplate c = t;
  const CompactRemap r = c.model.compact();
  const std::size_t n = c.model.nodes.slots.capacity();
  std::vector<std::string> names(n);
  std::vector<NodeEncoding> enc(n);
  std::vector<double> clr(t.encoded_clearance.empty() ? 0 : n);
  for (std::size_t i = 0; i < r.nodes.size(); ++i) {
    if (!r.nodes[i].valid()) continue;
    const std::uint32_t k = r.nodes[i].value;
    names[k] = t.node_names[i];
    enc[k] = t.encodings.nodes[i];
    if (!clr.empty()) clr[k] = t.encoded_clearance[i];
  }
  auto node = [&](std::uint32_t old) {
    if (old >= r.nodes.size() || !r.nodes[old].valid())
      refuse(t.name, "an encoding refers to dead node " + std::to_string(old));
    return r.nodes[old].value;
  };
  for (NodeEncoding& e : enc)
    if (e.mode == NodeEncodingMode::kOneToOne) e.element = node(e.element);
  for (NodeRef& ref : c.encodings.refs) ref.node = node(ref.node);
  c.node_names = std::move(names);
  c.encodings.nodes = std::move(enc);
  c.encoded_clearance = std::move(clr);
  for (TemplateProfile& p : c.profiles) p.halfedge = r.halfedge(p.halfedge);
  return c;
}

Json pair_of(const Model& m, HalfedgeIdx h) {
  return Json::array({m.tail(h).value, m.head(h).value});
}

// ------------------------------------------------------------------ tables

/// Refuses what the reader would refuse: a template that does not
/// validate, levels or a complex hole count outside the reader's ranges.
void check_writable(const ProfileTemplate& t) {
  if (Status s = validate_template(t); !s) refuse(t.name, "it does not validate: " + s.message());
  const Model& m = t.model;
  const std::string& tn = t.name;
  // The reader's ranges: a file this writes must read back.
  if (t.levels < 0 || t.levels > kMaxLevels) refuse(tn, "levels " + std::to_string(t.levels) + " outside [0, " + std::to_string(kMaxLevels) + "]");
  if (m.complex_holes < 0) refuse(tn, "negative complex hole count");
}

/// The format, version and scalar fields.
Json header(const ProfileTemplate& t) {
  const Model& m = t.model;
  const std::string& tn = t.name;
  Json doc = Json::object();
  doc["format"] = std::string(kTemplateFormat);
  doc["version"] = kTemplateFormatVersion;
  doc["name"] = t.name;
  doc["reference"] = t.reference;
  doc["clearance"] = num(t.clearance, tn, "clearance");
  doc["levels"] = t.levels;
  doc["complex_holes"] = m.complex_holes;
  return doc;
}

/// Surfaces with their faces (node cycles) and flags.
Json surfaces_json(const Model& m, const std::string& tn) {
  const std::size_t nf = m.faces.slots.capacity();
  // Faces are numbered in file order, surface after surface: their indices
  // survive only if the model groups them that way (the builders do).
  for (std::size_t f = 1; f < nf; ++f)
    if (m.faces.surface[f].value < m.faces.surface[f - 1].value)
      refuse(tn, "face " + std::to_string(f) + " of surface " + std::to_string(m.faces.surface[f].value) +
                     " follows a face of surface " + std::to_string(m.faces.surface[f - 1].value) +
                     " (faces must be grouped by surface)");
  Json surfaces = Json::array();
  std::vector<NodeIdx> cyc;
  for (std::size_t s = 0; s < m.surfaces.slots.capacity(); ++s) {
    Json js = Json::object();
    js["name"] = m.surfaces.name[s];
    if (m.surfaces.flags[s] != 0) js["flags"] = m.surfaces.flags[s];
    Json faces = Json::array();
    Json fflags = Json::array();
    bool any_flag = false;
    for (std::size_t f = 0; f < nf; ++f) {
      if (m.faces.surface[f].value != s) continue;
      m.face_nodes(FaceIdx{static_cast<std::uint32_t>(f)}, cyc);
      Json jf = Json::array();
      for (NodeIdx v : cyc) jf.push_back(v.value);
      faces.push_back(std::move(jf));
      fflags.push_back(m.faces.flags[f]);
      any_flag |= m.faces.flags[f] != 0;
    }
    js["faces"] = std::move(faces);
    if (any_flag) js["face_flags"] = std::move(fflags);
    surfaces.push_back(std::move(js));
  }
  return surfaces;
}

/// Nodes: name, surface, position, the columns that are set, encoding and
/// encoded clearance.
Json nodes_json(const ProfileTemplate& t) {
  const Model& m = t.model;
  const std::string& tn = t.name;
  const std::size_t nn = m.nodes.slots.capacity();
  Json nodes = Json::array();
  for (std::size_t v = 0; v < nn; ++v) {
    Json jn = Json::object();
    jn["name"] = t.node_names[v];
    jn["surface"] = m.nodes.surface[v].value;
    jn["position"] = vec(m.nodes.position[v], tn, "a node position");
    // Columns the builders leave at their defaults are only written when set.
    if (m.nodes.position_backup[v] != Vec3d::Zero())
      jn["position_backup"] = vec(m.nodes.position_backup[v], tn, "a backup position");
    if (m.nodes.uv[v] != Vec2d::Zero())
      jn["uv"] = Json::array({num(m.nodes.uv[v].x(), tn, "a uv"), num(m.nodes.uv[v].y(), tn, "a uv")});
    if (m.nodes.in_face[v].valid()) jn["in_face"] = m.nodes.in_face[v].value;
    const NodeEncoding& e = t.encodings.nodes[v];
    Json je = Json::object();
    je["mode"] = to_string(e.mode);
    je["feature_point"] = e.feature_point;
    je["element"] = e.element;
    je["t"] = num(e.t, tn, "an encoding parameter");
    je["coords"] = vec(e.coords, tn, "encoding coordinates");
    if (e.mode == NodeEncodingMode::kNToOne) {
      if (std::size_t{e.first_ref} + e.ref_count > t.encodings.refs.size())
        refuse(tn, "node " + std::to_string(v) + " refers past the reference pool");
      Json refs = Json::array();
      for (std::uint32_t k = 0; k < e.ref_count; ++k) {
        const NodeRef& r = t.encodings.refs[e.first_ref + k];
        Json jr = Json::object();
        jr["node"] = r.node;
        jr["delta"] = vec(r.delta, tn, "a reference delta");
        jr["weight"] = num(r.weight, tn, "a reference weight");
        refs.push_back(std::move(jr));
      }
      je["refs"] = std::move(refs);
    }
    jn["encoding"] = std::move(je);
    if (!t.encoded_clearance.empty()) jn["encoded_clearance"] = num(t.encoded_clearance[v], tn, "a clearance");
    nodes.push_back(std::move(jn));
  }
  return nodes;
}

/// Edges as node pairs (halfedge 2e from the first to the second), and
/// their flags when any is set.
void add_edges(const Model& m, Json& doc) {
  const std::size_t ne = m.edges.slots.capacity();
  Json edges = Json::array();
  Json eflags = Json::array();
  bool any_eflag = false;
  for (std::size_t e = 0; e < ne; ++e) {
    edges.push_back(pair_of(m, halfedge_of(EdgeIdx{static_cast<std::uint32_t>(e)}, 0)));
    eflags.push_back(m.edges.flags[e]);
    any_eflag |= m.edges.flags[e] != 0;
  }
  doc["edges"] = std::move(edges);
  if (any_eflag) doc["edge_flags"] = std::move(eflags);
}

/// Mesh edges as node chains.
Json mesh_edges_json(const Model& m, const std::string& tn) {
  Json mes = Json::array();
  for (std::size_t i = 0; i < m.mesh_edges.slots.capacity(); ++i) {
    const auto chain = m.mesh_edges.halfedges.row(i);
    Json jm = Json::object();
    jm["surface"] = m.mesh_edges.surface[i].value;
    Json jn = Json::array();
    for (std::size_t k = 0; k < chain.size(); ++k) {
      if (k == 0)
        jn.push_back(m.tail(chain[0]).value);
      else if (m.tail(chain[k]) != m.head(chain[k - 1]))
        refuse(tn, "mesh edge " + std::to_string(i) + " is not a connected chain");
      jn.push_back(m.head(chain[k]).value);
    }
    jm["nodes"] = std::move(jn);
    mes.push_back(std::move(jm));
  }
  return mes;
}

/// Mesh loops as lists of mesh edges.
Json mesh_loops_json(const Model& m) {
  Json loops = Json::array();
  for (std::size_t i = 0; i < m.mesh_loops.slots.capacity(); ++i) {
    Json jl = Json::object();
    jl["surface"] = m.mesh_loops.surface[i].value;
    Json list = Json::array();
    for (MeshEdgeIdx me : m.mesh_loops.mesh_edges.row(i)) list.push_back(me.value);
    jl["mesh_edges"] = std::move(list);
    loops.push_back(std::move(jl));
  }
  return loops;
}

/// Joints: their members (mesh edge and direction).
Json joints_json(const Model& m) {
  Json joints = Json::array();
  for (std::size_t i = 0; i < m.joints.slots.capacity(); ++i) {
    Json members = Json::array();
    for (const JointMember& jm : m.joints.members.row(i)) {
      Json x = Json::object();
      x["mesh_edge"] = jm.mesh_edge.value;
      x["positive"] = jm.positive;
      members.push_back(std::move(x));
    }
    Json jj = Json::object();
    jj["members"] = std::move(members);
    joints.push_back(std::move(jj));
  }
  return joints;
}

/// Attribute nodes on a vertex, an edge (halfedge as a node pair) or a face.
Json attribute_nodes_json(const Model& m, const std::string& tn) {
  Json anodes = Json::array();
  for (std::size_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
    const auto& a = m.attrib_nodes;
    Json ja = Json::object();
    ja["kind"] = attrib_kind_name(a.kind[i]);
    ja["surface"] = a.surface[i].value;
    switch (a.kind[i]) {
      case AttribNodeKind::kVertex:
        ja["node"] = a.element[i];
        break;
      case AttribNodeKind::kEdge:
        ja["halfedge"] = pair_of(m, HalfedgeIdx{a.element[i]});
        break;
      case AttribNodeKind::kFace:
        ja["face"] = a.element[i];
        ja["corner"] = a.corner[i];
        break;
    }
    ja["param"] = vec(a.param[i], tn, "an attribute parameter");
    ja["position"] = vec(a.position[i], tn, "an attribute position");
    anodes.push_back(std::move(ja));
  }
  return anodes;
}

/// Attribute edges as lists of attribute nodes.
Json attribute_edges_json(const Model& m) {
  Json aedges = Json::array();
  for (std::size_t i = 0; i < m.attrib_edges.slots.capacity(); ++i) {
    Json ja = Json::object();
    ja["surface"] = m.attrib_edges.surface[i].value;
    ja["feature_id"] = m.attrib_edges.feature_id[i];
    Json list = Json::array();
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(i)) list.push_back(a.value);
    ja["nodes"] = std::move(list);
    aedges.push_back(std::move(ja));
  }
  return aedges;
}

/// Profiles: halfedge, kind, shift mode and the Bezier offsets or the point list.
Json profiles_json(const ProfileTemplate& t) {
  const Model& m = t.model;
  const std::string& tn = t.name;
  Json profiles = Json::array();
  for (const TemplateProfile& p : t.profiles) {
    Json jp = Json::object();
    jp["halfedge"] = pair_of(m, p.halfedge);
    jp["kind"] = kind_name(p.kind);
    jp["shift"] = shift_name(p.shift);
    if (p.kind == ProfileCurve::Kind::kBezier) {
      Json off = Json::array();
      for (const Vec3d& o : p.bezier.offsets) off.push_back(vec(o, tn, "a Bezier offset"));
      jp["offsets"] = std::move(off);
    } else {
      jp["a"] = vec(p.points.a, tn, "a profile end");
      jp["b"] = vec(p.points.b, tn, "a profile end");
      Json u = Json::array();
      for (double x : p.points.u) u.push_back(num(x, tn, "a profile parameter"));
      jp["u"] = std::move(u);
      Json pts = Json::array();
      for (const Vec3d& q : p.points.points) pts.push_back(vec(q, tn, "a profile point"));
      jp["points"] = std::move(pts);
    }
    profiles.push_back(std::move(jp));
  }
  return profiles;
}

Json to_json(const ProfileTemplate& t) {
  check_writable(t);
  const Model& m = t.model;
  const std::string& tn = t.name;
  Json doc = header(t);
  doc["surfaces"] = surfaces_json(m, tn);
  doc["nodes"] = nodes_json(t);
  add_edges(m, doc);
  doc["mesh_edges"] = mesh_edges_json(m, tn);
  doc["mesh_loops"] = mesh_loops_json(m);
  doc["joints"] = joints_json(m);
  doc["attribute_nodes"] = attribute_nodes_json(m, tn);
  doc["attribute_edges"] = attribute_edges_json(m);
  doc["profiles"] = profiles_json(t);
  return doc;
}

/// Pretty printer: objects one member per line, arrays of scalars on one
/// line (positions, face cycles), arrays of containers one element per line.
/// Numbers go through nlohmann's dump, which writes the shortest decimal
/// that reads back to the same double.
void emit(const Json& j, int indent, std::string& out) {
  if (j.is_object()) {
    if (j.empty()) {
      out += "{}";
      return;
    }
    out += "{\n";
    bool first = true;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!first) out += ",\n";
      first = false;
      out.append(static_cast<std::size_t>(indent + 2), ' ');
      out += Json(it.key()).dump();
      out += ": ";
      emit(it.value(), indent + 2, out);
    }
    out += '\n';
    out.append(static_cast<std::size_t>(indent), ' ');
    out += '}';
  } else if (j.is_array()) {
    const bool flat = std::none_of(j.begin(), j.end(), [](const Json& x) { return x.is_structured(); });
    if (flat) {
      out += '[';
      for (std::size_t i = 0; i < j.size(); ++i) {
        if (i) out += ", ";
        out += j[i].dump();
      }
      out += ']';
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < j.size(); ++i) {
      if (i) out += ",\n";
      out.append(static_cast<std::size_t>(indent + 2), ' ');
      emit(j[i], indent + 2, out);
    }
    out += '\n';
    out.append(static_cast<std::size_t>(indent), ' ');
    out += ']';
  } else {
    out += j.dump();
  }
}
}  // namespace

std::string template_to_json_string(const ProfileTemplate& t) {
  const Json doc = has_tombstones_in_any_table(t.model) ? to_json(compacted(t)) : to_json(t);
  std::string out;
  emit(doc, 0, out);
  out += '\n';
  return out;
}

void write_template_json(const ProfileTemplate& t, const std::filesystem::path& path) {
  std::string text;
  try {
    text = template_to_json_string(t);
  } catch (const Error& e) {
    throw Error(Status(e.status().code(), path.string() + ": " + e.status().message()));
  }
  write_atomically(path, [&](AtomicFile& out) { out.write(text); });
}

}  // namespace atelier
