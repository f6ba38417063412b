#include <atelier/engine/status_format.h>
#include <atelier/io/atomic_file.h>
#include <atelier/systems/pattern/made_to_measure.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>

#include "made_to_measure_detail.h"

namespace atelier {

namespace {

/// The reference of warm starts is flattened with this many times the
/// iteration cap (MadeToMeasurePatterns::prepare).
constexpr int kReferenceIterations = 3;

void cell(std::string& out, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  out += buf;
}

/// CSV field: quoted when it holds a comma, quote or line break.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

}  // namespace

double sew_line_width(const PatternPiece& piece, double v) noexcept {
  std::vector<double> xs;
  for (const auto& loop : piece.sew_line)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec2d& a = loop[i];
      const Vec2d& b = loop[(i + 1) % loop.size()];
      if ((a.y() <= v) == (b.y() <= v)) continue;  // half-open: each crossing once
      xs.push_back(a.x() + (v - a.y()) / (b.y() - a.y()) * (b.x() - a.x()));
    }
  std::sort(xs.begin(), xs.end());
  double w = 0;
  for (std::size_t i = 0; i + 1 < xs.size(); i += 2) w += xs[i + 1] - xs[i];
  return w;
}

Status pattern_detail::check_named_lines(const MadeToMeasureOptions& opt) {
  for (const NamedLine& l : opt.lines)
    if (!std::isfinite(l.fraction) || l.fraction < 0 || l.fraction > 1)
      return status_of(ErrorCode::kInvalidArgument, "named line '", l.name, "': fraction ", l.fraction,
                       " is not in [0, 1]");
  return {};
}

namespace {

/// The file options for the opened model: surfaces named by the caller are
/// the garment's, mapped to the opened model's.
PatternFileOptions opened_options(const MadeToMeasureOptions& opt, const OpenedSeams& opened) {
  PatternFileOptions fo = opt.files;
  // Every piece of a named surface (marked seams may split it).
  auto remap = [&](std::vector<SurfaceIdx>& v) {
    std::vector<SurfaceIdx> o;
    for (SurfaceIdx s : v) {
      const std::size_t before = o.size();
      for (std::uint32_t t = 0; t < opened.part_of.size(); ++t)
        if (opened.part_of[t] == s) o.push_back(SurfaceIdx{t});
      if (o.size() == before) o.emplace_back();  // no such surface: refused downstream, as named
    }
    v = std::move(o);
  };
  remap(fo.flatten.surfaces);
  remap(fo.pattern.mirror);
  fo.flatten.seed_faces.clear();  // face indices do not carry over; pieces start at their largest triangle
  fo.pattern.seam_allowances.clear();
  return fo;
}

/// The summary, the measurements and the CSV of a written pattern set.
void finish(MadeToMeasureReport& rep, const MadeToMeasureOptions& opt, const std::filesystem::path& dir) {
  for (const PieceFlattening& p : rep.files.flattening.pieces) {
    rep.flipped += p.distortion.flipped;
    rep.max_length_error = std::max(rep.max_length_error, p.distortion.length_error);
  }
  for (const SeamCheck& c : rep.files.pattern.seams) {
    rep.failed_seams += c.ok ? 0 : 1;
    rep.max_seam_difference_mm = std::max(rep.max_seam_difference_mm, c.max_difference_mm);
  }
  std::string csv = "piece,kind,name,pattern_mm,body_mm\n";
  for (const PatternPiece& p : rep.files.pattern.pieces) {
    PieceMeasurements pm;
    pm.piece = p.name;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& loop : p.sew_line)
      for (const Vec2d& q : loop) {
        lo = std::min(lo, q.y());
        hi = std::max(hi, q.y());
      }
    if (!(hi >= lo)) lo = hi = 0;
    pm.height_mm = hi - lo;
    csv += field(p.name) + ",height,grain,";
    cell(csv, pm.height_mm);
    csv += ",\n";
    for (const NamedLine& l : opt.lines) {
      pm.widths_mm.push_back(sew_line_width(p, lo + l.fraction * (hi - lo)));
      csv += field(p.name) + ",width," + field(l.name) + ",";
      cell(csv, pm.widths_mm.back());
      csv += ",\n";
    }
    if (!p.mirrored)
      for (const SeamCheck& c : rep.files.pattern.seams)
        for (const SeamMemberLength& ml : c.members) {
          if (ml.surface != p.surface) continue;
          csv += field(p.name) + ",seam,joint" + std::to_string(c.joint.value) + ",";
          cell(csv, ml.length_2d_mm);
          csv += ",";
          cell(csv, ml.length_3d_mm);
          csv += "\n";
        }
    rep.measurements.push_back(std::move(pm));
  }
  if (opt.csv) {
    rep.files.files.push_back(dir / "measurements.csv");
    write_atomically(rep.files.files.back(), [&](AtomicFile& f) { f.write(csv); });
  }
}

/// The corners of every live face of an opened model, in its order: where
/// its fan starts (open_seams picks the corner from the geometry: a polygon
/// whose fan from its first corner has a nearly degenerate triangle starts
/// at another, seams.cpp fan_start).
std::vector<std::uint32_t> fans(const Model& m) {
  std::vector<std::uint32_t> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
    if (m.alive(FaceIdx{f})) m.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) { c.push_back(m.tail(h).value); });
  return c;
}

/// The topology write() compares with prepare()'s: node slots, and per live
/// face its surface and nodes.
std::vector<std::uint32_t> fingerprint(const Model& m) {
  std::vector<std::uint32_t> fp{static_cast<std::uint32_t>(m.nodes.slots.capacity()),
                                static_cast<std::uint32_t>(m.faces.slots.capacity())};
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    fp.push_back(f);
    fp.push_back(m.faces.surface[f].value);
    m.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) { fp.push_back(m.tail(h).value); });
  }
  return fp;
}

}  // namespace

Expected<MadeToMeasureReport> write_made_to_measure_pattern(const Model& garment, const MadeToMeasureOptions& opt,
                                                            const std::filesystem::path& dir, const ExecContext& ctx) {
  if (Status st = pattern_detail::check_named_lines(opt); !st) return st;
  auto opened = open_seams(garment, opt.seams, ctx);
  if (!opened) return opened.status();
  MadeToMeasureReport rep;
  rep.seams_opened = opened->paths.size();
  auto files = write_pattern_files(opened->model, opened_options(opt, *opened), dir, ctx);
  if (!files) return files.status();
  rep.files = std::move(*files);
  finish(rep, opt, dir);
  return rep;
}

// ------------------------------------------------------ MadeToMeasurePatterns

struct MadeToMeasurePatterns::Impl {
  MadeToMeasureOptions opt;
  PatternFileOptions files;
  OpenedSeams opened;  // the reference's, its pattern in model.nodes.uv
  ModelFlattener reference;
  std::vector<std::uint32_t> topology;
  std::vector<std::uint32_t> fans;  // the opened reference's (fans())
  mutable std::mutex pool_mutex;
  mutable std::vector<std::unique_ptr<ModelFlattener>> pool;  // idle workspaces
};

MadeToMeasurePatterns::MadeToMeasurePatterns() = default;
MadeToMeasurePatterns::~MadeToMeasurePatterns() = default;
MadeToMeasurePatterns::MadeToMeasurePatterns(MadeToMeasurePatterns&&) noexcept = default;
MadeToMeasurePatterns& MadeToMeasurePatterns::operator=(MadeToMeasurePatterns&&) noexcept = default;

Status MadeToMeasurePatterns::prepare(const Model& reference, const MadeToMeasureOptions& opt, const ExecContext& ctx) {
  impl_.reset();
  if (Status st = pattern_detail::check_named_lines(opt); !st) return st;
  auto impl = std::make_unique<Impl>();
  impl->opt = opt;
  auto opened = open_seams(reference, opt.seams, ctx);
  if (!opened) return opened.status();
  impl->opened = std::move(*opened);
  impl->files = opened_options(opt, impl->opened);
  Model& m = impl->opened.model;
  // With warm starts the reference's pattern is every body's start: it is
  // flattened with kReferenceIterations times the iteration cap (once per
  // batch), so the bodies start from a converged pattern, not from one a
  // Tutte start left at the cap (docs/performance.md, flat11).
  FlattenOptions reference_options = impl->files.flatten;
  if (opt.warm_start) reference_options.max_iterations *= kReferenceIterations;
  if (Status st = impl->reference.build(m, reference_options); !st) return st;
  std::vector<Vec2d> uv(m.nodes.slots.capacity(), Vec2d::Zero());
  auto flat = impl->reference.flatten(m.nodes.position, uv, false, ctx);
  if (!flat) return flat.status();
  m.nodes.uv = std::move(uv);
  impl->topology = fingerprint(reference);
  impl->fans = fans(m);
  impl_ = std::move(impl);
  return {};
}

Expected<MadeToMeasureReport> MadeToMeasurePatterns::write(const Model& garment, const std::filesystem::path& dir,
                                                           const ExecContext& ctx) const {
  if (!impl_) return Status(ErrorCode::kInvalidArgument, "made-to-measure patterns: prepare() was not called");
  const Impl& I = *impl_;
  if (fingerprint(garment) != I.topology)
    return Status(ErrorCode::kInvalidArgument,
                  "made-to-measure patterns: the garment does not have the topology of the reference they were "
                  "prepared for");
  // The body's own opened model: its seams are the reference's (open_seams
  // chooses them from the topology), but a polygon's fan may start at
  // another corner (fan_start looks at the geometry): the one-shot form's
  // triangles, so that cold the bits are the one-shot's on every piece.
  auto opened = open_seams(garment, I.opt.seams, ctx);
  if (!opened) return opened.status();
  Model& m = opened->model;
  if (m.nodes.slots.capacity() != I.opened.model.nodes.slots.capacity() ||
      m.faces.slots.capacity() != I.opened.model.faces.slots.capacity() || opened->part_of != I.opened.part_of)
    return Status(ErrorCode::kInternal,
                  "made-to-measure patterns: the garment's seams open otherwise than the "
                  "reference's");
  m.nodes.uv = I.opened.model.nodes.uv;  // the warm start's pattern
  // A workspace from the pool when every polygon is fanned as on the
  // reference; else one built for this body (its pieces fanned otherwise
  // start warm with the reference's multipliers, not its factor).
  const bool reference_fans = fans(m) == I.fans;
  std::unique_ptr<ModelFlattener> ws;
  if (reference_fans) {
    const std::lock_guard<std::mutex> lock(I.pool_mutex);
    if (!I.pool.empty()) {
      ws = std::move(I.pool.back());
      I.pool.pop_back();
    }
  }
  if (!ws) {
    ws = std::make_unique<ModelFlattener>();
    if (Status st = ws->build(reference_fans ? I.opened.model : m, I.files.flatten); !st) return st;
  }
  Expected<FlattenReport> flat = Status(ErrorCode::kInternal, "made-to-measure patterns: not flattened");
  if (!I.opt.warm_start)
    flat = ws->flatten(m.nodes.position, m.nodes.uv, false, ctx);
  else if (Status st = ws->warm_from(I.reference); !st)
    flat = st;
  else
    flat = ws->flatten(m.nodes.position, m.nodes.uv, true, ctx);
  if (reference_fans) {
    const std::lock_guard<std::mutex> lock(I.pool_mutex);
    I.pool.push_back(std::move(ws));
  }
  if (!flat) return flat.status();
  MadeToMeasureReport rep;
  rep.seams_opened = I.opened.paths.size();
  auto files = write_pattern_files(m, std::move(*flat), I.files, dir);
  if (!files) return files.status();
  rep.files = std::move(*files);
  finish(rep, I.opt, dir);
  return rep;
}

}  // namespace atelier
