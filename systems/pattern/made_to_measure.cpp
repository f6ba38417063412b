#include <atelier/engine/status_format.h>
#include <atelier/io/atomic_file.h>
#include <atelier/systems/pattern/made_to_measure.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace atelier {

namespace {

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

Expected<MadeToMeasureReport> write_made_to_measure_pattern(const Model& garment, const MadeToMeasureOptions& opt,
                                                            const std::filesystem::path& dir, const ExecContext& ctx) {
  for (const NamedLine& l : opt.lines)
    if (!std::isfinite(l.fraction) || l.fraction < 0 || l.fraction > 1)
      return status_of(ErrorCode::kInvalidArgument, "named line '", l.name, "': fraction ", l.fraction,
                       " is not in [0, 1]");
  auto opened = open_seams(garment, opt.seams, ctx);
  if (!opened) return opened.status();
  MadeToMeasureReport rep;
  rep.seams_opened = opened->paths.size();
  PatternFileOptions fo = opt.files;
  // Surfaces named by the caller are the garment's: map them to the opened model.
  auto remap = [&](std::vector<SurfaceIdx>& v) {
    for (SurfaceIdx& s : v) s = s.value < opened->surfaces.size() ? opened->surfaces[s.value] : SurfaceIdx{};
  };
  remap(fo.flatten.surfaces);
  remap(fo.pattern.mirror);
  fo.flatten.seed_faces.clear();  // face indices do not carry over; pieces start at their largest triangle
  fo.pattern.seam_allowances.clear();
  Model& m = opened->model;
  auto files = write_pattern_files(m, fo, dir, ctx);
  if (!files) return files.status();
  rep.files = std::move(*files);
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
  return rep;
}

}  // namespace atelier
