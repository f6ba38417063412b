// Model::compact() (storage/model.h): drops the tombstones of every table
// and renumbers the references between tables.
#include <atelier/storage/model.h>

#include <vector>

namespace atelier {

namespace {
template <class Tag>
Idx<Tag> map_idx(const std::vector<Idx<Tag>>& remap, Idx<Tag> i) {
  return i.valid() ? remap[i.value] : i;
}
}  // namespace

CompactRemap Model::compact() {
  CompactRemap r;
  r.nodes = nodes.slots.compact();
  r.edges = edges.slots.compact();
  r.faces = faces.slots.compact();
  r.surfaces = surfaces.slots.compact();
  r.mesh_edges = mesh_edges.slots.compact();
  r.mesh_loops = mesh_loops.slots.compact();
  r.joints = joints.slots.compact();
  r.attrib_nodes = attrib_nodes.slots.compact();
  r.attrib_edges = attrib_edges.slots.compact();
  auto mh = [&](HalfedgeIdx h) { return h.valid() ? r.halfedge(h) : h; };

  // Nodes.
  const std::size_t nn = nodes.slots.capacity();
  compact_column(nodes.position, r.nodes, nn);
  compact_column(nodes.position_backup, r.nodes, nn);
  compact_column(nodes.uv, r.nodes, nn);
  compact_column(nodes.out, r.nodes, nn);
  compact_column(nodes.surface, r.nodes, nn);
  compact_column(nodes.in_face, r.nodes, nn);
  nodes.props.compact(r.nodes, nn);
  for (auto& h : nodes.out) h = mh(h);
  for (auto& s : nodes.surface) s = map_idx(r.surfaces, s);
  for (auto& f : nodes.in_face) f = map_idx(r.faces, f);

  // Edges and halfedges.
  const std::size_t ne = edges.slots.capacity();
  compact_column(edges.flags, r.edges, ne);
  compact_column(edges.mesh_edge, r.edges, ne);
  edges.props.compact(r.edges, ne);
  for (auto& m : edges.mesh_edge) m = map_idx(r.mesh_edges, m);
  {
    std::vector<HalfedgeIdx> hr(2 * r.edges.size());
    for (std::size_t e = 0; e < r.edges.size(); ++e)
      for (unsigned s = 0; s < 2; ++s)
        hr[2 * e + s] = r.edges[e].valid() ? halfedge_of(r.edges[e], s) : HalfedgeIdx{};
    compact_column(halfedges.tail, hr, 2 * ne);
    halfedges.props.compact(hr, 2 * ne);
    compact_column(halfedges.face, hr, 2 * ne);
    compact_column(halfedges.next, hr, 2 * ne);
    compact_column(halfedges.prev, hr, 2 * ne);
    compact_column(halfedges.vnext, hr, 2 * ne);
    compact_column(halfedges.vprev, hr, 2 * ne);
    for (auto& v : halfedges.tail) v = map_idx(r.nodes, v);
    for (auto& f : halfedges.face) f = map_idx(r.faces, f);
    for (auto* c : {&halfedges.next, &halfedges.prev, &halfedges.vnext, &halfedges.vprev})
      for (auto& h : *c) h = mh(h);
  }

  // Faces.
  const std::size_t nf = faces.slots.capacity();
  compact_column(faces.halfedge, r.faces, nf);
  compact_column(faces.surface, r.faces, nf);
  compact_column(faces.flags, r.faces, nf);
  faces.props.compact(r.faces, nf);
  for (auto& h : faces.halfedge) h = mh(h);
  for (auto& s : faces.surface) s = map_idx(r.surfaces, s);

  // Surfaces.
  const std::size_t ns = surfaces.slots.capacity();
  compact_column(surfaces.name, r.surfaces, ns);
  compact_column(surfaces.flags, r.surfaces, ns);
  surfaces.props.compact(r.surfaces, ns);

  // Mesh edges, loops, joints.
  const std::size_t nm = mesh_edges.slots.capacity();
  compact_column(mesh_edges.surface, r.mesh_edges, nm);
  compact_column(mesh_edges.loop, r.mesh_edges, nm);
  compact_column(mesh_edges.joint, r.mesh_edges, nm);
  mesh_edges.halfedges.compact(r.mesh_edges, nm);
  for (auto& s : mesh_edges.surface) s = map_idx(r.surfaces, s);
  for (auto& l : mesh_edges.loop) l = map_idx(r.mesh_loops, l);
  for (auto& j : mesh_edges.joint) j = map_idx(r.joints, j);
  mesh_edges.halfedges.transform_values(mh);

  const std::size_t nl = mesh_loops.slots.capacity();
  compact_column(mesh_loops.surface, r.mesh_loops, nl);
  mesh_loops.mesh_edges.compact(r.mesh_loops, nl);
  for (auto& s : mesh_loops.surface) s = map_idx(r.surfaces, s);
  mesh_loops.mesh_edges.transform_values([&](MeshEdgeIdx m) { return map_idx(r.mesh_edges, m); });

  joints.members.compact(r.joints, joints.slots.capacity());
  joints.members.transform_values([&](JointMember m) {
    m.mesh_edge = map_idx(r.mesh_edges, m.mesh_edge);
    return m;
  });

  // Attributes.
  const std::size_t na = attrib_nodes.slots.capacity();
  auto& an = attrib_nodes;
  compact_column(an.kind, r.attrib_nodes, na);
  compact_column(an.element, r.attrib_nodes, na);
  compact_column(an.corner, r.attrib_nodes, na);
  compact_column(an.param, r.attrib_nodes, na);
  compact_column(an.position, r.attrib_nodes, na);
  compact_column(an.owner, r.attrib_nodes, na);
  compact_column(an.surface, r.attrib_nodes, na);
  for (std::size_t i = 0; i < na; ++i) {
    switch (an.kind[i]) {
      case AttribNodeKind::kVertex: an.element[i] = r.nodes[an.element[i]].value; break;
      case AttribNodeKind::kEdge: an.element[i] = r.halfedge(HalfedgeIdx{an.element[i]}).value; break;
      case AttribNodeKind::kFace: an.element[i] = r.faces[an.element[i]].value; break;
    }
    an.owner[i] = map_idx(r.attrib_edges, an.owner[i]);
    an.surface[i] = map_idx(r.surfaces, an.surface[i]);
  }
  const std::size_t nae = attrib_edges.slots.capacity();
  auto& ae = attrib_edges;
  compact_column(ae.surface, r.attrib_edges, nae);
  compact_column(ae.feature_id, r.attrib_edges, nae);
  ae.nodes.compact(r.attrib_edges, nae);
  ae.props.compact(r.attrib_edges, nae);
  for (auto& s : ae.surface) s = map_idx(r.surfaces, s);
  ae.nodes.transform_values([&](AttribNodeIdx a) { return map_idx(r.attrib_nodes, a); });

  ++topology_version;
  return r;
}
}  // namespace atelier
