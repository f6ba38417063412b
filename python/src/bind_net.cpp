// Net Booleans, trimming and rounding off (systems/net, seed 004): the
// calls of `atelier boolean`, `atelier trim` and `atelier round`, each over
// the same one library call (net_boolean, trim_net, round_off), with nets
// given as a Mesh (read_mesh: the CLI's reading, net_polygons of the file's
// model, so the same bits) or a (vertices, faces) pair.
#include <atelier/storage/builder.h>
#include <atelier/systems/net/boolean.h>
#include <atelier/systems/net/round_off.h>
#include <atelier/systems/net/trim.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"

namespace atelier::python {

namespace {

/// A net as the CLI reads it: a Mesh read from a file through
/// net_polygons (the file's vertices, welded as the reader marked them),
/// arrays as given.
PolygonSoup net_arg(const MeshLike& obj, const char* what) {
  const std::shared_ptr<const Mesh> mesh = mesh_from(obj, what);
  if (mesh->model) return net_polygons(*mesh->model);
  return mesh->soup;
}

template <class T>
T named(Expected<T>&& e, const char* what_a, const char* what_b) {
  if (e) return std::move(*e);
  std::string msg = e.status().message();
  if (msg.rfind("net A", 0) == 0) msg = std::string(what_a) + ": " + msg;
  if (what_b && msg.rfind("net B", 0) == 0) msg = std::string(what_b) + ": " + msg;
  raise(Status(e.status().code(), msg));
}

/// (vertices, faces) of a soup result: views onto a Mesh that owns it.
py::tuple soup_out(PolygonSoup&& soup) {
  auto mesh = std::make_shared<Mesh>();
  mesh->soup = std::move(soup);
  py::object obj = py::cast(std::shared_ptr<Mesh>(mesh));
  return py::make_tuple(obj.attr("vertices"), obj.attr("faces"));
}

}  // namespace

void bind_net(py::module_& m) {
  py::class_<PreparedNet>(m, "PreparedNet", R"doc(
A closed net prepared once for Booleans (systems/net/boolean.h,
PreparedNet): split into triangles, checked (closed, oriented outwards,
manifold, no duplicate vertices, not self-intersecting unless
``self_check=False``) and given its box hierarchy. ``boolean`` takes it in
place of a mesh and does none of this again; several threads may use it
at once. A chain A - B1 - B2 - ... prepares each tool once and takes each
result as ``report["prepared"]`` (``prepare_result=True``), checked once.
)doc")
      .def(py::init([](const MeshLike& net, bool self_check, int threads, const Progress& progress) {
             PrepareOptions o;
             o.check_self_intersection = self_check;
             const PolygonSoup s = net_arg(net, "net");
             return named(
                 run_long(progress, threads, [&](const ExecContext& ctx) { return PreparedNet::prepare(s, o, ctx); }),
                 "net", nullptr);
           }),
           py::arg("net"), py::kw_only(), py::arg("self_check") = true, py::arg("threads") = 0,
           py::arg("progress") = py::none(), R"doc(
net: a Mesh or a (vertices, faces) pair, closed and consistently oriented.
self_check: test it for self-intersections (a Boolean asking for the test
    refuses a net prepared without it).
Long call. Raises ValueError with the engine's message (naming the face).
)doc")
      .def_property_readonly("volume", &PreparedNet::volume)
      .def_property_readonly("area", &PreparedNet::area)
      .def_property_readonly("triangles", &PreparedNet::triangle_count)
      .def_property_readonly("self_checked", &PreparedNet::self_checked);

  m.def(
      "boolean",
      [](const MeshLike& a, const MeshLike& b, const std::string& op, const std::string& mode,
         const std::string& correspondence, const std::string& join, const std::string& rule, bool self_check,
         bool exact_refinement, bool prepare_result, bool check_result, int threads, const Progress& progress) {
        BooleanOptions o;
        o.op = unwrap(parse_boolean_op(op));
        o.mode = unwrap(parse_boolean_mode(mode));
        o.correspondence = unwrap(parse_correspondence(correspondence));
        o.join = unwrap(parse_boolean_join(join));
        o.rule = unwrap(parse_connect_rule(rule));
        o.check_self_intersection = self_check;
        o.exact_refinement = exact_refinement;
        o.prepare_result = prepare_result;
        o.check_result = check_result;
        BooleanReport r;
        if (py::isinstance<PreparedNet>(a) || py::isinstance<PreparedNet>(b) || prepare_result) {
          // A mesh operand is prepared (named "A" or "B", as the one-call
          // names the nets); a PreparedNet is used as it is.
          std::array<std::optional<PreparedNet>, 2> given;
          std::array<PolygonSoup, 2> soups;
          for (int k = 0; k < 2; ++k) {
            const MeshLike& x = k == 0 ? a : b;
            if (py::isinstance<PreparedNet>(x))
              given[k] = x.cast<PreparedNet>();
            else
              soups[k] = net_arg(x, k == 0 ? "a" : "b");
          }
          r = named(run_long(progress, threads,
                             [&](const ExecContext& ctx) -> Expected<BooleanReport> {
                               std::array<PreparedNet, 2> p;
                               for (int k = 0; k < 2; ++k) {
                                 if (given[k]) {
                                   p[k] = *given[k];
                                   continue;
                                 }
                                 PrepareOptions po;
                                 po.name = k == 0 ? "A" : "B";
                                 po.check_self_intersection = self_check;
                                 auto made = PreparedNet::prepare(std::move(soups[k]), po, ctx);
                                 if (!made) return made.status();
                                 p[k] = std::move(*made);
                               }
                               return net_boolean(p[0], p[1], o, ctx);
                             }),
                    "a", "b");
        } else {
          const PolygonSoup sa = net_arg(a, "a"), sb = net_arg(b, "b");
          r = named(run_long(progress, threads, [&](const ExecContext& ctx) { return net_boolean(sa, sb, o, ctx); }),
                    "a", "b");
        }
        py::dict rep;
        rep["volume"] = py::dict(py::arg("a") = r.volume_a, py::arg("b") = r.volume_b, py::arg("result") = r.volume);
        rep["area"] = py::dict(py::arg("a") = r.area_a, py::arg("b") = r.area_b, py::arg("result") = r.area);
        rep["intersection_polygons"] = r.intersection_polygons;
        rep["candidate_pairs"] = r.candidate_pairs;
        rep["intersecting_pairs"] = r.intersecting_pairs;
        rep["intersection_points"] = r.intersection_points;
        rep["cut_triangles"] = r.cut_triangles;
        rep["refined_exact"] = r.refined_exact;
        const auto seam_size = static_cast<py::ssize_t>(r.seam.size());
        rep["seam"] = adopt(std::move(r.seam), {seam_size});
        if (o.mode == BooleanMode::kPaper) {
          rep["merged_pairs"] = r.merged_pairs;
          rep["valence"] = py::dict(py::arg("vertices") = r.valence.vertices,
                                    py::arg("irregular") = r.valence.irregular, py::arg("min") = r.valence.min,
                                    py::arg("max") = r.valence.max, py::arg("mean") = r.valence.mean);
        }
        if (o.join == BooleanJoin::kMeshes)
          rep["connecting"] = py::dict(py::arg("triangles") = r.connecting.triangles,
                                       py::arg("quads") = r.connecting.quads, py::arg("other") = r.connecting.other,
                                       py::arg("irregular_vertices") = r.connecting.irregular_vertices);
        if (prepare_result) {
          if (r.prepared_status)
            rep["prepared"] = py::cast(std::move(r.prepared));
          else
            rep["prepared_error"] = r.prepared_status.message();
        }
        py::tuple vf = soup_out(std::move(r.result));
        return py::make_tuple(vf[0], vf[1], rep);
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("op") = "union", py::arg("mode") = "exact",
      py::arg("correspondence") = "visual", py::arg("join") = "cut", py::arg("rule") = "a",
      py::arg("self_check") = true, py::arg("exact_refinement") = false, py::arg("prepare_result") = false,
      py::arg("check_result") = true, py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Union, intersection or difference of two closed nets (``atelier boolean``; seed 004).

a, b: the nets, each a Mesh (``read_mesh``), a (vertices, faces) pair
    (closed and consistently oriented) or a PreparedNet (not prepared again:
    the same bits as the meshes it was made from).
op: "union", "intersection", "difference" (a minus b) or "b-a".
mode: "exact" (watertight, default) or "paper" (merged midpoints, Fig. 2).
correspondence: paper mode: "visual", "topological", "window2", "window4".
join: "cut" (section 3) or "meshes" (connecting meshes, section 4).
rule: with join="meshes": "a", "b", "c" (triangles) or "i", "ii", "iii" (quads).
self_check: test the inputs for self-intersections first.
exact_refinement: re-triangulate every cut triangle with the exact
    constrained triangulation instead of the certified double fast path
    (``--exact-refinement``; the results differ at most in the diagonals).
prepare_result: also return the result as a PreparedNet in
    ``report["prepared"]`` (with prepare's checks, self-intersection
    included: rounding can fold a sliver), or the reason it cannot be one
    in ``report["prepared_error"]`` (an empty or self-crossing result).
check_result: exact mode: repair the result once its new points are
    rounded to doubles and refuse it (ValueError naming two triangles) if it
    still crosses itself (on by default; a certificate decides most results,
    at 1.07-1.6x the unchecked Boolean; False, ``--no-check-result``: the
    rounded result unchecked).

Returns (vertices, faces, report): the result's (n, 3) float64 vertices and
faces (views onto the result, zero copy; the same bits as the CLI for the
same files), and a dict: ``volume`` and ``area`` (``a``, ``b``,
``result``), ``intersection_polygons``, ``candidate_pairs``,
``intersecting_pairs``, ``intersection_points``, ``cut_triangles``,
``refined_exact`` (of them, those the exact triangulation re-triangulated),
``seam`` (uint32 result vertices on the intersection polygons, for
``round_off``), and in paper mode ``merged_pairs`` and ``valence``.
Long call (GIL released, Ctrl-C cancels). Raises ValueError with the
engine's message (naming ``a`` or ``b``) for open or self-intersecting nets.
)doc");

  m.def(
      "trim",
      [](const MeshLike& net, const Array& curve, double height, bool keep_enclosed, int threads,
         const Progress& progress) {
        const PolygonSoup s = net_arg(net, "net");
        const std::vector<Vec3d> c = points_from(curve, "curve");
        if (!(height >= 0) || !std::isfinite(height)) value_error("height: a finite number >= 0");
        TrimOptions o;
        o.height = height;
        o.keep_enclosed = keep_enclosed;
        TrimReport r =
            named(run_long(progress, threads, [&](const ExecContext& ctx) { return trim_net(s, c, o, ctx); }), "net",
                  nullptr);
        py::dict rep;
        rep["area"] = py::dict(py::arg("before") = r.area_before, py::arg("after") = r.area_after);
        rep["cut_points"] = r.cut_points;
        rep["parts"] = r.parts;
        py::tuple band = soup_out(std::move(r.band));
        rep["band"] = band;
        py::tuple vf = soup_out(std::move(r.result));
        return py::make_tuple(vf[0], vf[1], rep);
      },
      py::arg("net"), py::arg("curve"), py::kw_only(), py::arg("height") = 0.0, py::arg("keep_enclosed") = false,
      py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Trims a net by a closed curve on it (``atelier trim``; seed 004 section 6).

net: a Mesh or a (vertices, faces) pair, open or closed.
curve: (k, 3) points of the closed curve (k >= 3; ``atelier trim``'s curve
    file holds the same points, one "x y z" per line).
height: half height of the band extruded from the curve (0: twice the
    net's mean edge length).
keep_enclosed: keep the part the curve encloses instead of the rest.

Returns (vertices, faces, report): the trimmed net (views) and a dict with
``area`` (``before``, ``after``), ``cut_points``, ``parts`` and ``band``
(the extruded band as (vertices, faces)). Long call. Raises ValueError with
the engine's message for a bad curve or net.
)doc");

  m.def(
      "round_off",
      [](const MeshLike& net, const Array& seam, double mu, double nu, int rings, int threads,
         const Progress& progress) {
        const std::shared_ptr<const Mesh> mesh = mesh_from(net, "net");
        Model model;
        if (mesh->model) {
          model = *mesh->model;
        } else {
          (void)unwrap(add_polygon_surface(model, "net", mesh->soup));
        }
        const py::array ids = py::module_::import("numpy").attr("asarray")(seam);
        if (ids.ndim() != 1 || (ids.size() > 0 && ids.dtype().kind() != 'i' && ids.dtype().kind() != 'u'))
          value_error("seam: expected a 1-D array of vertex indices");
        const auto idx = py::module_::import("numpy").attr("asarray")(ids, "int64").cast<py::array_t<std::int64_t>>();
        // Seam indices are the mesh's vertex indices: through the reader's
        // source_vertex for a file's model, as `atelier round` maps them.
        const auto source = model.nodes.props.find<std::int32_t>("source_vertex");
        std::vector<NodeIdx> nodes;
        for (py::ssize_t k = 0; k < idx.size(); ++k) {
          const std::int64_t id = idx.at(k);
          NodeIdx found;
          if (id >= 0)
            for (std::uint32_t v = 0; v < model.nodes.slots.capacity() && !found.valid(); ++v)
              if (model.alive(NodeIdx{v}) && (source.valid() ? source[NodeIdx{v}] == id : v == id)) found = NodeIdx{v};
          if (!found.valid())
            value_error("seam: seam[" + std::to_string(k) + "] = " + std::to_string(id) +
                        " is not a vertex of the net (" + std::to_string(mesh->positions().size()) + " vertices)");
          nodes.push_back(found);
        }
        RoundOptions o;
        o.mu = mu;
        o.nu = nu;
        o.rings = rings;
        const RoundReport r = unwrap(
            run_long(progress, threads, [&](const ExecContext& ctx) { return round_off(model, nodes, o, ctx); }));
        py::dict rep;
        rep["energy"] = py::dict(py::arg("before") = r.energy_before, py::arg("after") = r.energy_after);
        rep["free_vertices"] = r.free_nodes;
        rep["terms"] = r.terms;
        rep["moved"] = r.moved;
        py::object out = py::cast(mesh_of(std::move(model)));
        return py::make_tuple(out.attr("vertices"), out.attr("faces"), rep);
      },
      py::arg("net"), py::arg("seam"), py::kw_only(), py::arg("mu") = 1.0, py::arg("nu") = 1.0, py::arg("rings") = 1,
      py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Rounds off a seam by the umbrella energy (``atelier round``; seed 004 section 6).

net: a Mesh or a (vertices, faces) pair.
seam: 1-D integer array of the net's vertex indices on the seam (the
    ``seam`` of ``boolean``'s report).
mu, nu: weights of curvature and torsion (>= 0).
rings: free the vertices within this many edges of the seam.

Returns (vertices, faces, report): the rounded net (views; faces unchanged)
and a dict with ``energy`` (``before``, ``after``), ``free_vertices``,
``terms`` and ``moved``. Long call. Raises ValueError for a seam index that
is not a vertex or for bad weights.
)doc");
}

}  // namespace atelier::python
