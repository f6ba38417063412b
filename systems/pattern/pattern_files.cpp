// SVG, DXF and strain-map writers, and write_pattern_files (pattern_files.h).
// They live in systems/pattern, not io/: they serialise this family's own
// types (pieces with allowances, notches, grain lines), which io/ (below
// systems/) cannot see; the bytes still go through io/atomic_file.h.
#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/systems/pattern/pattern_files.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <set>

namespace atelier {

namespace {

/// Shortest text that reads back to the same double (std::to_chars).
void num(std::string& out, double v) {
  if (v == 0) v = 0;  // no "-0"
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

[[nodiscard]] std::string xml_escape(std::string_view s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    }
  }
  return o;
}

/// Letters, digits, '-' and '_' kept; everything else '_'.
[[nodiscard]] std::string safe_name(std::string_view s) {
  std::string o;
  for (char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return o.empty() ? std::string("piece") : o;
}

struct Bounds {
  Vec2d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2d hi = -lo;
  void add(const Vec2d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
};

[[nodiscard]] Bounds bounds(const PatternPiece& p) {
  Bounds b;
  for (const auto& loops : {&p.cut_line, &p.sew_line})
    for (const auto& l : *loops)
      for (const Vec2d& q : l) b.add(q);
  return b;
}

// ------------------------------------------------------------------- SVG

void svg_points(std::string& o, const std::vector<Vec2d>& pts) {
  o += "points=\"";
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (i) o += ' ';
    num(o, pts[i].x());
    o += ',';
    num(o, -pts[i].y());
  }
  o += '"';
}

void svg_line(std::string& o, const Vec2d& a, const Vec2d& b) {
  o += "<line x1=\"";
  num(o, a.x());
  o += "\" y1=\"";
  num(o, -a.y());
  o += "\" x2=\"";
  num(o, b.x());
  o += "\" y2=\"";
  num(o, -b.y());
  o += "\"/>\n";
}

// ------------------------------------------------------------------- DXF

void dxf(std::string& o, int code, std::string_view value) {
  o += std::to_string(code);
  o += '\n';
  o += value;
  o += '\n';
}
void dxf(std::string& o, int code, double value) {
  o += std::to_string(code);
  o += '\n';
  num(o, value);
  o += '\n';
}
void dxf_polyline(std::string& o, std::string_view layer, const std::vector<Vec2d>& pts, bool closed) {
  dxf(o, 0, "POLYLINE");
  dxf(o, 8, layer);
  dxf(o, 66, "1");
  dxf(o, 10, 0.0);
  dxf(o, 20, 0.0);
  dxf(o, 30, 0.0);
  dxf(o, 70, closed ? "1" : "0");
  for (const Vec2d& p : pts) {
    dxf(o, 0, "VERTEX");
    dxf(o, 8, layer);
    dxf(o, 10, p.x());
    dxf(o, 20, p.y());
    dxf(o, 30, 0.0);
  }
  dxf(o, 0, "SEQEND");
  dxf(o, 8, layer);
}
void dxf_line(std::string& o, std::string_view layer, const Vec2d& a, const Vec2d& b) {
  dxf(o, 0, "LINE");
  dxf(o, 8, layer);
  dxf(o, 10, a.x());
  dxf(o, 20, a.y());
  dxf(o, 30, 0.0);
  dxf(o, 11, b.x());
  dxf(o, 21, b.y());
  dxf(o, 31, 0.0);
}

/// DXF text: printable ASCII only (R12 files name no code page we could rely on).
[[nodiscard]] std::string dxf_text(std::string_view s) {
  std::string o;
  for (char c : s) o += (c >= 0x20 && c < 0x7f) ? c : '_';
  return o;
}

/// Notch slit: from the sew line across the allowance (3 mm inwards when
/// there is no allowance, so the notch stays visible).
[[nodiscard]] std::array<Vec2d, 2> slit(const PatternNotch& n) {
  if (n.depth > 0) return {n.at, n.at + n.depth * n.outward};
  return {n.at, n.at - 3.0 * n.outward};
}

}  // namespace

std::string pattern_svg(const PatternPiece& p) {
  const Bounds b = bounds(p);
  const double margin = 5;
  const Vec2d lo = b.lo - Vec2d(margin, margin), hi = b.hi + Vec2d(margin, margin);
  const double W = hi.x() - lo.x(), H = hi.y() - lo.y();
  std::string o;
  o += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  o += "<!-- Atelier pattern piece '" + xml_escape(p.name) +
       "': 1 user unit = 1 mm, x = u, y = -v (grain along -y); layers are the groups "
       "boundary (cut line), sew_line, seam_allowance, notches, grain_line, piece_label -->\n";
  o += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"";
  num(o, W);
  o += "mm\" height=\"";
  num(o, H);
  o += "mm\" viewBox=\"";
  num(o, lo.x());
  o += ' ';
  num(o, -hi.y());
  o += ' ';
  num(o, W);
  o += ' ';
  num(o, H);
  o += "\">\n";
  o += "<g id=\"boundary\" fill=\"none\" stroke=\"#000\" stroke-width=\"0.5\">\n";
  for (const auto& l : p.cut_line) {
    o += "<polygon ";
    svg_points(o, l);
    o += "/>\n";
  }
  o += "</g>\n<g id=\"sew_line\" fill=\"none\" stroke=\"#06c\" stroke-width=\"0.3\" stroke-dasharray=\"3 1.5\">\n";
  for (const auto& l : p.sew_line) {
    o += "<polygon ";
    svg_points(o, l);
    o += "/>\n";
  }
  o += "</g>\n<g id=\"seam_allowance\" fill=\"none\" stroke=\"#999\" stroke-width=\"0.2\">\n";
  for (const AllowanceRun& r : p.allowances) {
    o += "<polyline data-seam=\"" + (r.seam.valid() ? std::to_string(r.seam.value) : std::string("hem")) +
         "\" data-width-mm=\"";
    num(o, r.width_mm);
    o += "\" ";
    svg_points(o, r.edge);
    o += "/>\n";
  }
  o += "</g>\n<g id=\"notches\" stroke=\"#c00\" stroke-width=\"0.5\">\n";
  for (const PatternNotch& n : p.notches) {
    const auto s = slit(n);
    svg_line(o, s[0], s[1]);
  }
  o += "</g>\n<g id=\"grain_line\" stroke=\"#000\" stroke-width=\"0.5\" fill=\"#000\">\n";
  svg_line(o, p.grain_line[0], p.grain_line[1]);
  {  // arrow head at the +v end
    const Vec2d t = p.grain_line[1];
    const std::vector<Vec2d> head{t, t + Vec2d(-2, -6), t + Vec2d(2, -6)};
    o += "<polygon ";
    svg_points(o, head);
    o += "/>\n";
  }
  o += "</g>\n<g id=\"piece_label\" font-family=\"sans-serif\" font-size=\"10\" text-anchor=\"middle\">\n<text x=\"";
  num(o, p.label_at.x());
  o += "\" y=\"";
  num(o, -p.label_at.y());
  o += "\">" + xml_escape(p.name) + "</text>\n</g>\n</svg>\n";
  return o;
}

std::string pattern_dxf(const PatternSet& set) {
  std::string o;
  dxf(o, 999,
      "Atelier pattern (ASTM D6673 / AAMA layers: 1 boundary, 4 notches, 7 grain line, 14 sew line, "
      "15 piece label; SEAM_ALLOWANCE per-seam allowance edges); units: millimetres");
  dxf(o, 0, "SECTION");
  dxf(o, 2, "HEADER");
  dxf(o, 9, "$ACADVER");
  dxf(o, 1, "AC1009");
  dxf(o, 9, "$INSUNITS");
  dxf(o, 70, "4");
  dxf(o, 9, "$MEASUREMENT");
  dxf(o, 70, "1");
  dxf(o, 0, "ENDSEC");
  dxf(o, 0, "SECTION");
  dxf(o, 2, "TABLES");
  dxf(o, 0, "TABLE");
  dxf(o, 2, "LTYPE");
  dxf(o, 70, "1");
  dxf(o, 0, "LTYPE");
  dxf(o, 2, "CONTINUOUS");
  dxf(o, 70, "0");
  dxf(o, 3, "Solid line");
  dxf(o, 72, "65");
  dxf(o, 73, "0");
  dxf(o, 40, 0.0);
  dxf(o, 0, "ENDTAB");
  const std::pair<const char*, const char*> layers[] = {
      {"0", "7"}, {"1", "7"}, {"4", "1"}, {"7", "3"}, {"14", "5"}, {"15", "7"}, {"SEAM_ALLOWANCE", "8"}};
  dxf(o, 0, "TABLE");
  dxf(o, 2, "LAYER");
  dxf(o, 70, std::to_string(std::size(layers)));
  for (const auto& [name, colour] : layers) {
    dxf(o, 0, "LAYER");
    dxf(o, 2, name);
    dxf(o, 70, "0");
    dxf(o, 62, colour);
    dxf(o, 6, "CONTINUOUS");
  }
  dxf(o, 0, "ENDTAB");
  dxf(o, 0, "ENDSEC");
  std::vector<std::string> names;
  std::set<std::string> used;
  for (const PatternPiece& p : set.pieces) {
    std::string n = safe_name(p.name);
    for (int k = 2; used.count(n); ++k) n = safe_name(p.name) + "_" + std::to_string(k);
    used.insert(n);
    names.push_back(n);
  }
  dxf(o, 0, "SECTION");
  dxf(o, 2, "BLOCKS");
  for (std::size_t i = 0; i < set.pieces.size(); ++i) {
    const PatternPiece& p = set.pieces[i];
    dxf(o, 0, "BLOCK");
    dxf(o, 8, "0");
    dxf(o, 2, names[i]);
    dxf(o, 70, "0");
    dxf(o, 10, 0.0);
    dxf(o, 20, 0.0);
    dxf(o, 30, 0.0);
    dxf(o, 3, names[i]);
    for (const auto& l : p.cut_line) dxf_polyline(o, "1", l, true);
    for (const auto& l : p.sew_line) dxf_polyline(o, "14", l, true);
    for (const AllowanceRun& r : p.allowances) dxf_polyline(o, "SEAM_ALLOWANCE", r.edge, false);
    for (const PatternNotch& n : p.notches) {
      const auto s = slit(n);
      dxf_line(o, "4", s[0], s[1]);
    }
    dxf_line(o, "7", p.grain_line[0], p.grain_line[1]);
    dxf(o, 0, "TEXT");
    dxf(o, 8, "15");
    dxf(o, 10, p.label_at.x());
    dxf(o, 20, p.label_at.y());
    dxf(o, 30, 0.0);
    dxf(o, 40, 10.0);
    dxf(o, 1, "Piece Name: " + dxf_text(p.name));
    dxf(o, 0, "ENDBLK");
    dxf(o, 8, "0");
  }
  dxf(o, 0, "ENDSEC");
  dxf(o, 0, "SECTION");
  dxf(o, 2, "ENTITIES");
  double x = 0;
  for (std::size_t i = 0; i < set.pieces.size(); ++i) {
    const Bounds b = bounds(set.pieces[i]);
    dxf(o, 0, "INSERT");
    dxf(o, 8, "0");
    dxf(o, 2, names[i]);
    dxf(o, 10, x - b.lo.x());
    dxf(o, 20, -b.lo.y());
    dxf(o, 30, 0.0);
    x += b.hi.x() - b.lo.x() + 20;
  }
  dxf(o, 0, "ENDSEC");
  dxf(o, 0, "EOF");
  return o;
}

void write_pattern_svg(const PatternPiece& piece, const std::filesystem::path& path) {
  const std::string s = pattern_svg(piece);
  write_atomically(path, [&](AtomicFile& f) { f.write(s); });
}

void write_pattern_dxf(const PatternSet& set, const std::filesystem::path& path) {
  const std::string s = pattern_dxf(set);
  write_atomically(path, [&](AtomicFile& f) { f.write(s); });
}

RgbImage strain_map(const Model& m, const PieceFlattening& piece, double units_to_mm, double px_per_mm, double range) {
  if (!(px_per_mm > 0) || !(range > 0) || !(units_to_mm > 0))
    throw Error(Status(ErrorCode::kInvalidArgument, "strain_map: resolution, range and units must be positive"));
  Bounds b;
  for (const auto& t : piece.triangle_nodes)
    for (NodeIdx v : t) b.add(units_to_mm * m.nodes.uv[v.value]);
  if (piece.triangle_nodes.empty()) throw Error(Status(ErrorCode::kInvalidArgument, "strain_map: empty piece"));
  const double margin = 4;
  const Vec2d size = b.hi - b.lo + Vec2d(2 * margin, 2 * margin);
  // At most 4096 pixels on the long side.
  const double scale = std::min(px_per_mm, 4096.0 / std::max(size.x(), size.y()));
  const auto W = static_cast<std::uint32_t>(std::max(1.0, std::ceil(size.x() * scale)));
  const auto H = static_cast<std::uint32_t>(std::max(1.0, std::ceil(size.y() * scale)));
  RgbImage img(W, H, 255);
  auto to_px = [&](NodeIdx v) {
    const Vec2d q = units_to_mm * m.nodes.uv[v.value] - b.lo + Vec2d(margin, margin);
    return Vec2d(q.x() * scale, static_cast<double>(H) - q.y() * scale);
  };
  auto colour = [&](double e, std::uint8_t* px) {
    // Diverging blue - light grey - red (Moreland's cool-warm end points).
    const double t = std::clamp(e / range, -1.0, 1.0);
    const double grey[3] = {221, 221, 221}, blue[3] = {59, 76, 192}, red[3] = {180, 4, 38};
    const double* end = t < 0 ? blue : red;
    const double a = std::abs(t);
    for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>(std::lround((1 - a) * grey[c] + a * end[c]));
  };
  for (std::size_t f = 0; f < piece.triangle_nodes.size(); ++f) {
    const Vec2d a = to_px(piece.triangle_nodes[f][0]), bb = to_px(piece.triangle_nodes[f][1]),
                c = to_px(piece.triangle_nodes[f][2]);
    const Vec2d s = piece.stretch[f];
    const double e = std::abs(s.x() - 1) >= std::abs(s.y() - 1) ? s.x() - 1 : s.y() - 1;
    const double x0 = std::floor(std::min({a.x(), bb.x(), c.x()})), x1 = std::ceil(std::max({a.x(), bb.x(), c.x()}));
    const double y0 = std::floor(std::min({a.y(), bb.y(), c.y()})), y1 = std::ceil(std::max({a.y(), bb.y(), c.y()}));
    const double den = (bb - a).x() * (c - a).y() - (bb - a).y() * (c - a).x();
    if (den == 0) continue;
    for (double y = std::max(0.0, y0); y < std::min<double>(H, y1 + 1); ++y)
      for (double x = std::max(0.0, x0); x < std::min<double>(W, x1 + 1); ++x) {
        const Vec2d p(x + 0.5, y + 0.5);
        const double l1 = ((p - a).x() * (c - a).y() - (p - a).y() * (c - a).x()) / den;
        const double l2 = ((bb - a).x() * (p - a).y() - (bb - a).y() * (p - a).x()) / den;
        if (l1 >= 0 && l2 >= 0 && l1 + l2 <= 1)
          colour(e, img.at(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)));
      }
  }
  // The boundary (edges of one triangle only) in black.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> sides;
  for (const auto& t : piece.triangle_nodes)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = t[k].value, v = t[(k + 1) % 3].value;
      sides.emplace_back(std::min(u, v), std::max(u, v));
    }
  std::sort(sides.begin(), sides.end());
  for (std::size_t i = 0; i < sides.size(); ++i) {
    const bool twice = (i + 1 < sides.size() && sides[i + 1] == sides[i]) || (i > 0 && sides[i - 1] == sides[i]);
    if (twice) continue;
    const Vec2d a = to_px(NodeIdx{sides[i].first}), c = to_px(NodeIdx{sides[i].second});
    const int steps = static_cast<int>(std::ceil((c - a).norm() * 2)) + 1;
    for (int k = 0; k <= steps; ++k) {
      const Vec2d p = a + (c - a) * (static_cast<double>(k) / steps);
      const auto x = static_cast<std::int64_t>(p.x()), y = static_cast<std::int64_t>(p.y());
      if (x >= 0 && y >= 0 && x < W && y < H) {
        std::uint8_t* px = img.at(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
        px[0] = px[1] = px[2] = 0;
      }
    }
  }
  return img;
}

Expected<PatternFilesReport> write_pattern_files(Model& m, const PatternFileOptions& opt,
                                                 const std::filesystem::path& dir, const ExecContext& ctx) {
  if (!(opt.strain_map_px_per_mm > 0) || !(opt.strain_map_range > 0))
    return Status(ErrorCode::kInvalidArgument, "pattern files: strain-map resolution and range must be positive");
  auto flat = flatten_surfaces(m, opt.flatten, ctx);
  if (!flat) return flat.status();
  return write_pattern_files(m, std::move(*flat), opt, dir);
}

Expected<PatternFilesReport> write_pattern_files(const Model& m, FlattenReport flattening,
                                                 const PatternFileOptions& opt, const std::filesystem::path& dir) {
  if (!(opt.strain_map_px_per_mm > 0) || !(opt.strain_map_range > 0))
    return Status(ErrorCode::kInvalidArgument, "pattern files: strain-map resolution and range must be positive");
  PatternFilesReport rep;
  rep.flattening = std::move(flattening);
  std::vector<SurfaceIdx> pieces;
  for (const PieceFlattening& p : rep.flattening.pieces) pieces.push_back(p.surface);
  auto pat = make_pattern(m, pieces, opt.pattern);
  if (!pat) return pat.status();
  rep.pattern = std::move(*pat);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(Status(ErrorCode::kIo, dir.string() + ": cannot create the folder: " + ec.message()));
  std::set<std::string> used;
  auto unique = [&](const std::string& base) {
    std::string n = base;
    for (int k = 2; used.count(n); ++k) n = base + "_" + std::to_string(k);
    used.insert(n);
    return n;
  };
  for (const PatternPiece& p : rep.pattern.pieces) {
    const std::string stem = unique(safe_name(m.surfaces.name[p.surface.value]) + (p.mirrored ? "_mirrored" : ""));
    if (opt.svg) {
      rep.files.push_back(dir / (stem + ".svg"));
      write_pattern_svg(p, rep.files.back());
    }
    if (opt.strain_maps && !p.mirrored) {
      const auto it = std::find_if(rep.flattening.pieces.begin(), rep.flattening.pieces.end(),
                                   [&](const PieceFlattening& f) { return f.surface == p.surface; });
      rep.files.push_back(dir / (unique(stem + "_strain") + ".png"));
      write_png(strain_map(m, *it, opt.pattern.units_to_mm, opt.strain_map_px_per_mm, opt.strain_map_range),
                rep.files.back());
    }
  }
  if (opt.dxf) {
    rep.files.push_back(dir / "pattern.dxf");
    write_pattern_dxf(rep.pattern, rep.files.back());
  }
  if (opt.model) {
    rep.files.push_back(dir / "pattern.atm");
    write_model(m, rep.files.back());
  }
  return rep;
}

}  // namespace atelier
