#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/sketch/sketch.h>

#include <algorithm>
#include <sstream>

namespace atelier {

namespace {

/// Deletes painted curves again (their nodes were appended by painting and
/// nothing else refers to them): the live tables are as before painting.
void erase_curves(Model& m, const std::vector<AttribEdge>& curves) {
  for (const AttribEdge& e : curves) {
    if (!m.alive(e)) continue;
    const auto row = m.attrib_edges.nodes.row(e.idx.value);
    std::vector<AttribNodeIdx> nodes(row.begin(), row.end());
    m.delete_attrib_edge(e.idx);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (AttribNodeIdx a : nodes)
      if (m.alive(a)) m.delete_attrib_node(a);
  }
}

std::string label(const StrokeFile& f, std::size_t i) {
  std::ostringstream o;
  o << "stroke " << i << " (" << to_string(f.strokes[i].tool);
  if (!f.strokes[i].name.empty()) o << " '" << f.strokes[i].name << "'";
  o << ")";
  return o.str();
}

/// Paints a stroke and records it in the report.
Status paint_into(Model& m, const Camera& cam, const Stroke& s, bool through, const SketchOptions& opt,
                  const ExecContext& ctx, StrokeReport& rep) {
  PaintOptions po;
  po.through = through;
  po.surfaces = opt.surfaces;
  auto r = paint_stroke(m, s.camera.value_or(cam), s.points, po, ctx);
  if (!r) return r.status();
  for (const PaintedCurve& c : r->curves) {
    rep.curve_lengths.push_back(c.length);
    rep.curve_closed.push_back(c.closed);
    rep.curves.insert(rep.curves.end(), c.edges.begin(), c.edges.end());
  }
  return {};
}

}  // namespace

Expected<SketchReport> apply_strokes(Model& m, const StrokeFile& file, const SketchOptions& opt,
                                     const ExecContext& ctx) {
  if (Status s = file.camera.check(); !s) return Status(ErrorCode::kInvalidArgument, "sketch: " + s.message());
  Model backup;
  if (!opt.keep_going) backup = m;
  SketchReport out;
  const Camera& cam = file.camera;
  std::size_t i = 0;
  while (i < file.strokes.size()) {
    if (ctx.cancelled()) {
      if (!opt.keep_going) m = std::move(backup);
      return Status(ErrorCode::kCancelled, "sketch cancelled");
    }
    const Stroke& s = file.strokes[i];
    StrokeReport rep;
    rep.stroke = i;
    rep.tool = s.tool;
    rep.through = s.through;
    rep.name = s.name;
    Status st;
    switch (s.tool) {
      case StrokeTool::kPaint:
      case StrokeTool::kPaintThrough:
        st = paint_into(m, cam, s, s.tool == StrokeTool::kPaintThrough, opt, ctx, rep);
        break;
      case StrokeTool::kCut: {
        CutOptions co;
        co.retriangulate = opt.retriangulate;
        if (i + 1 < file.strokes.size() && file.strokes[i + 1].tool == StrokeTool::kPick) {
          rep.strokes = 2;
          auto p = locate_pixel(m, file.strokes[i + 1].camera.value_or(cam), file.strokes[i + 1].points.at(0),
                                opt.surfaces, ctx);
          if (!p) {
            st = Status(p.status().code(), label(file, i + 1) + ": " + p.status().message());
            break;
          }
          co.pick = p->location;
        }
        st = paint_into(m, cam, s, s.through, opt, ctx, rep);
        if (!st) break;
        auto r = cut_along_curves(m, rep.curves, co, ctx);
        if (!r) {
          erase_curves(m, rep.curves);
          st = r.status();
          break;
        }
        rep.faces_added = r->faces_added;
        rep.nodes_added = r->nodes_added;
        rep.faces_removed = r->faces_removed;
        rep.crossings = r->crossings;
        rep.pieces = r->pieces;
        rep.removed_area = r->removed_area;
        break;
      }
      case StrokeTool::kPartition: {
        std::size_t j = i;
        while (j < file.strokes.size() && file.strokes[j].tool == StrokeTool::kPartition) {
          st = paint_into(m, cam, file.strokes[j], file.strokes[j].through, opt, ctx, rep);
          if (!st) {
            st = Status(st.code(), label(file, j) + ": " + st.message());
            break;
          }
          ++j;
        }
        rep.strokes = j - i;
        if (!st) {
          erase_curves(m, rep.curves);
          break;
        }
        PartitionOptions po;
        po.retriangulate = opt.retriangulate;
        auto r = partition_along_curves(m, rep.curves, po, ctx);
        if (!r) {
          erase_curves(m, rep.curves);
          st = r.status();
          break;
        }
        rep.faces_added = r->faces_added;
        rep.nodes_added = r->nodes_added;
        rep.crossings = r->crossings;
        rep.pieces = r->pieces;
        break;
      }
      case StrokeTool::kExtrude: {
        auto in = extrusion_from_file(file, i);
        if (!in) {
          st = in.status();
          break;
        }
        rep.strokes = 1 + in->sweep.size();
        ExtrudeOptions eo;
        eo.surfaces = opt.surfaces;
        eo.retriangulate = opt.retriangulate;
        auto r = extrude(m, *in, eo, ctx);
        if (!r) {
          st = r.status();
          break;
        }
        rep.faces_added = r->faces_added;
        rep.nodes_added = r->nodes_added;
        rep.faces_removed = r->faces_removed;
        break;
      }
      case StrokeTool::kPick:
        st = Status(ErrorCode::kInvalidArgument, "a pick stroke must follow a cut stroke");
        break;
    }
    if (!st) {
      if (st.message().rfind("stroke ", 0) != 0) st = Status(st.code(), label(file, i) + ": " + st.message());
      rep.curves.clear();
      rep.curve_lengths.clear();
      rep.curve_closed.clear();
      rep.pieces.clear();
      rep.status = st;
      ++out.failed;
      if (!opt.keep_going) {
        m = std::move(backup);
        return st;
      }
    }
    i += rep.strokes;
    out.tools.push_back(std::move(rep));
    ctx.report("sketch: strokes", i, file.strokes.size());
  }
  return out;
}

}  // namespace atelier
