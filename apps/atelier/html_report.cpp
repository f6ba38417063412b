// The self-contained HTML report (html_report.h).
//
// Why this file is long: the page is one document; its summary, charts,
// worst-rows tables, colour bars and CSV share the escaping, labelling and
// number-formatting helpers of this file, which would otherwise be exported.
#include "html_report.h"

#include <atelier/engine/status.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>
#include <atelier/io/png.h>
#include <atelier/systems/view/colour_map.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <unordered_set>

namespace atelier {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Error bad(std::string_view what) {
  return Error(Status(ErrorCode::kInvalidArgument, "html report: " + std::string(what)));
}

void escape_into(std::string& out, std::string_view s) {
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out.push_back(c);
    }
  }
}

std::string escape(std::string_view s) {
  std::string out;
  escape_into(out, s);
  return out;
}

// Numbers with up to 6 significant digits (tables are for reading, the JSON
// keeps the exact values); integers as integers.
std::string format_number(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof buf, static_cast<long long>(v));
    return {buf, r.ptr};
  }
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 6);
  return {buf, r.ptr};
}

std::string cell(const json& v) {
  if (v.is_null()) return "&ndash;";
  if (v.is_number()) return format_number(v.get<double>());
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_string()) return escape(v.get_ref<const std::string&>());
  return escape(v.dump());
}

bool scalar(const json& v) {
  return v.is_null() || v.is_number() || v.is_string() || v.is_boolean();
}

const json& rows_of(const json& report) {
  static const json kEmpty = json::array();
  if (!report.is_object()) throw bad("the report must be a JSON object");
  const auto it = report.find("rows");
  if (it == report.end()) return kEmpty;
  if (!it->is_array()) throw bad("\"rows\" must be an array");
  for (std::size_t i = 0; i < it->size(); ++i) {
    const json& r = (*it)[i];
    if (!r.is_object()) throw bad("rows[" + std::to_string(i) + "] is not an object");
    for (const auto& [k, v] : r.items())
      if (!scalar(v)) throw bad("rows[" + std::to_string(i) + "]." + k + " is not a scalar");
  }
  return *it;
}

double quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

struct KnownKey {
  std::string_view key, label, unit;
  double scale;
  int digits;
  bool lower_is_worse;
};

// The summary keys `demo` and `regen` write.
constexpr KnownKey kKnownKeys[] = {
    {"bodies", "Bodies", "", 1, 3, false},
    {"completed", "Bodies completed", "", 1, 3, false},
    {"failed", "Bodies failed", "", 1, 3, false},
    {"bodies_with_penetration", "Bodies with garment vertices inside the body", "", 1, 3, false},
    {"worst_penetration_m", "Deepest penetration", "mm", 1000, 2, false},
    {"profile_nodes_under_shorts_total", "Profile-template nodes under the shorts (all bodies)", "", 1, 3, false},
    {"mean_edge_strain_p95", "Mean edge strain (95th percentile)", "%", 100, 2, false},
    {"mean_clearance_change_rms_m", "Mean clearance change (RMS per body)", "mm", 1000, 2, false},
    {"profile_template_nodes_inside", "Profile-template nodes inside the body (all bodies)", "", 1, 3, false},
    {"profile_template_max_crack_m", "Largest profile-template crack", "mm", 1000, 2, false},
    {"pattern_pieces", "Pattern pieces", "", 1, 3, false},
    {"pattern_flipped_triangles", "Flipped pattern triangles", "", 1, 3, false},
    {"pattern_max_seam_difference_mm", "Largest seam length difference", "mm", 1, 2, false},
    {"inside_nodes_total", "Garment vertices inside the body (all bodies)", "", 1, 3, false},
    {"layer_inside_vertices_total", "Garment vertices inside a lower layer (all bodies)", "", 1, 3, false},
    {"max_crack_m", "Largest profile-template crack", "mm", 1000, 2, false},
    {"mean_decode_ms_per_body", "Mean decode time per body", "ms", 1, 2, false},
    {"encode_s", "Encoding time", "s", 1, 2, false},
    {"total_s", "Total time", "s", 1, 3, false},
    {"bodies_per_s", "Throughput", "bodies/s", 1, 3, false},
};

// Per-garment figures: "<garment>_<phrase key>[unit suffix]".
struct KnownPhrase {
  std::string_view base, label;
  int digits;
  bool lower_is_worse;
};
constexpr KnownPhrase kPhrases[] = {
    {"min_clearance", "smallest clearance", 2, true},
    {"min_distance", "smallest distance to the body", 2, true},
    {"clearance_error", "largest clearance error (|distance - target clearance|)", 2, false},
    {"clearance_change", "clearance change", 2, false},
    {"edge_strain_p95", "edge strain (95th percentile)", 2, false},  // before its suffix strain_p95
    {"strain_p95", "edge strain (95th percentile)", 2, false},
    {"in_lower_layer", "vertices inside a lower layer", 3, false},
    {"inside", "vertices inside the body", 3, false},
    {"inside_vertices", "vertices inside the body", 3, false},
    {"crack", "largest crack", 2, false},
    {"profile_error", "profile error", 2, false},
    {"max_depth", "deepest penetration", 2, false},
    {"decode", "decode time", 2, false},
};

std::string humanise(std::string_view s) {
  std::string out(s);
  std::replace(out.begin(), out.end(), '_', ' ');
  return out;
}

std::string capitalised(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = static_cast<char>(s[0] - 'a' + 'A');
  return s;
}

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

// Fixed notation with `decimals` digits after the point.
std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::max(0, decimals), v);
  std::string s = buf;
  if (s == "-0" || (s.size() > 1 && s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos)) s.erase(0, 1);
  return s;
}

// The SVG id / anchor of a column: letters, digits, '-' and '_' only.
std::string slug(std::string_view s) {
  std::string out;
  for (char c : s) out.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '-');
  return out;
}

std::string csv_field(const json& v) {
  if (v.is_null()) return {};
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  q += '"';
  return q;
}

// An inline SVG histogram of one column (shown values), axis labels in its unit.
std::string histogram_svg(const std::string& key, const FigureLabel& fl, const std::vector<double>& shown,
                          const std::string& noun) {
  const Histogram hg = histogram(shown);
  if (hg.counts.empty()) return {};
  constexpr double W = 320, H = 180, L = 44, R = 12, T = 12, B = 44;
  const std::size_t top = *std::max_element(hg.counts.begin(), hg.counts.end());
  const double pw = W - L - R, ph = H - T - B, bw = pw / static_cast<double>(hg.counts.size());
  const std::string axis = fl.unit.empty() ? fl.label : fl.label + " (" + fl.unit + ")";
  auto num = [](double v) { return fixed(v, 1); };
  std::string s = "<svg class=\"hist\" id=\"hist-" + slug(key) + "\" data-key=\"" + escape(key) +
                  "\" width=\"320\" height=\"180\" viewBox=\"0 0 320 180\" "
                  "role=\"img\" aria-label=\"histogram of " +
                  escape(axis) + "\">";
  s += "<title>" + escape(axis) + ": " + std::to_string(shown.size()) + " values in " +
       std::to_string(hg.counts.size()) + " bins</title>";
  for (std::size_t i = 0; i < hg.counts.size(); ++i) {
    const double h = top ? ph * static_cast<double>(hg.counts[i]) / static_cast<double>(top) : 0.0;
    s += "<rect class=\"bin\" data-count=\"" + std::to_string(hg.counts[i]) + "\" x=\"" +
         num(L + bw * static_cast<double>(i) + 0.5) + "\" y=\"" + num(T + ph - h) + "\" width=\"" +
         num(std::max(bw - 1.0, 0.5)) + "\" height=\"" + num(h) + "\" fill=\"#4a78b5\"><title>" +
         format_significant(hg.edges[i], fl.digits) + " to " + format_significant(hg.edges[i + 1], fl.digits) + ": " +
         std::to_string(hg.counts[i]) + "</title></rect>";
  }
  s += "<line x1=\"" + num(L) + "\" y1=\"" + num(T + ph) + "\" x2=\"" + num(L + pw) + "\" y2=\"" + num(T + ph) +
       "\" stroke=\"#333\"/><line x1=\"" + num(L) + "\" y1=\"" + num(T) + "\" x2=\"" + num(L) + "\" y2=\"" +
       num(T + ph) + "\" stroke=\"#333\"/>";
  const std::string tick = "font-size=\"10\" fill=\"#333\"";
  // Integer bins (edges at k - 0.5) are labelled by their first and last value.
  const bool integer_bins = hg.edges.front() + 0.5 == std::floor(hg.edges.front() + 0.5) &&
                            hg.edges.back() - hg.edges.front() == static_cast<double>(hg.counts.size()) &&
                            std::all_of(shown.begin(), shown.end(), [](double v) { return v == std::floor(v); });
  const double first = integer_bins ? hg.edges.front() + 0.5 : hg.edges.front();
  const double last = integer_bins ? hg.edges.back() - 0.5 : hg.edges.back();
  s += "<text " + tick + " x=\"" + num(L) + "\" y=\"" + num(T + ph + 12) + "\" text-anchor=\"start\">" +
       (integer_bins ? format_number(first) : format_significant(first, fl.digits)) + "</text>";
  s += "<text " + tick + " x=\"" + num(L + pw) + "\" y=\"" + num(T + ph + 12) + "\" text-anchor=\"end\">" +
       (integer_bins ? format_number(last) : format_significant(last, fl.digits)) + "</text>";
  s += "<text " + tick + " x=\"" + num(L - 4) + "\" y=\"" + num(T + 8) + "\" text-anchor=\"end\">" +
       std::to_string(top) + "</text><text " + tick + " x=\"" + num(L - 4) + "\" y=\"" + num(T + ph) +
       "\" text-anchor=\"end\">0</text>";
  s += "<text class=\"xlabel\" font-size=\"11\" x=\"" + num(L + pw / 2) + "\" y=\"" + num(H - 8) +
       "\" text-anchor=\"middle\">" + escape(axis) + "</text>";
  s += "<text class=\"ylabel\" font-size=\"11\" transform=\"translate(12," + num(T + ph / 2) +
       ") rotate(-90)\" text-anchor=\"middle\">" + escape(noun) + "</text></svg>";
  return s;
}

constexpr std::string_view kStyle = R"(
body{font-family:sans-serif;margin:1.5em;color:#222;background:#fff}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.5em}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.25em .6em}th{background:#f0f0f0;cursor:pointer}
td.n{text-align:right;font-variant-numeric:tabular-nums}
.pics{display:flex;flex-wrap:wrap;gap:1em}
figure{margin:0;border:1px solid #ddd;padding:.5em;background:#fafafa}
figure img{display:block;max-width:360px;height:auto;image-rendering:auto}
figcaption{font-size:.85em;margin-top:.3em;max-width:360px}
.note{color:#666;font-size:.85em}
.charts{display:flex;flex-wrap:wrap;gap:1em}
.charts figure{padding:.3em}
.worst-tables{display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}
.worst-tables table{margin:0}
caption{font-size:.9em;text-align:left;padding:.2em 0}
.bar{display:flex;align-items:center;gap:.4em;font-size:.85em;margin-top:.3em}
.bar img{width:200px;height:14px;image-rendering:pixelated}
)";

// Decode check for headless browsers, and click-to-sort on table headers.
constexpr std::string_view kScript = R"(
function atelierImagesDecoded(){
  var imgs=Array.prototype.slice.call(document.images);
  var ok=imgs.every(function(i){return i.complete&&i.naturalWidth>0;});
  document.body.setAttribute('data-images-decoded', ok?String(imgs.length):'failed');
}
window.addEventListener('load', atelierImagesDecoded);
document.addEventListener('click', function(e){
  var th=e.target; if(th.tagName!=='TH')return;
  var table=th.closest('table'), body=table.tBodies[0], col=th.cellIndex;
  var asc=th.getAttribute('data-asc')!=='1'; th.setAttribute('data-asc', asc?'1':'0');
  var rows=Array.prototype.slice.call(body.rows);
  rows.sort(function(a,b){
    var x=a.cells[col].textContent, y=b.cells[col].textContent, fx=parseFloat(x), fy=parseFloat(y);
    var r=(!isNaN(fx)&&!isNaN(fy))?fx-fy:x.localeCompare(y); return asc?r:-r;});
  rows.forEach(function(r){body.appendChild(r);});
});
)";

}  // namespace

std::vector<std::string> report_columns(const json& report) {
  const json& rows = rows_of(report);
  std::vector<std::string> cols;
  if (const auto it = report.find("columns"); it != report.end()) {
    if (!it->is_array()) throw bad("\"columns\" must be an array of strings");
    for (const json& c : *it) {
      if (!c.is_string()) throw bad("\"columns\" must be an array of strings");
      cols.push_back(c.get<std::string>());
    }
    return cols;
  }
  std::unordered_set<std::string> seen;
  for (const json& r : rows)
    for (const auto& [k, v] : r.items())
      if (seen.insert(k).second) cols.push_back(k);
  return cols;
}

std::vector<ColumnStats> column_statistics(const json& report) {
  const json& rows = rows_of(report);
  std::vector<ColumnStats> out;
  for (const std::string& c : report_columns(report)) {
    std::vector<double> v;
    bool numeric = true;
    for (const json& r : rows) {
      const auto it = r.find(c);
      if (it == r.end() || it->is_null()) continue;
      if (!it->is_number()) {
        numeric = false;
        break;
      }
      v.push_back(it->get<double>());
    }
    if (!numeric || v.empty()) continue;
    std::sort(v.begin(), v.end());
    ColumnStats s;
    s.column = c;
    s.count = v.size();
    s.min = v.front();
    s.max = v.back();
    s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
    s.median = quantile(v, 0.5);
    s.p95 = quantile(v, 0.95);
    out.push_back(s);
  }
  return out;
}

std::vector<std::size_t> worst_rows(const json& report, std::string_view column, std::size_t k, bool largest) {
  const json& rows = rows_of(report);
  std::vector<std::pair<double, std::size_t>> v;
  const std::string key(column);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto it = rows[i].find(key);
    if (it != rows[i].end() && it->is_number()) v.emplace_back(it->get<double>(), i);
  }
  std::stable_sort(v.begin(), v.end(),
                   [&](const auto& a, const auto& b) { return largest ? a.first > b.first : a.first < b.first; });
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < std::min(k, v.size()); ++i) out.push_back(v[i].second);
  return out;
}

std::string base64_encode(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t w = (std::uint32_t{p[i]} << 16) | (std::uint32_t{p[i + 1]} << 8) | p[i + 2];
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(w >> s) & 63]);
  }
  if (const std::size_t rest = bytes.size() - i; rest) {
    std::uint32_t w = std::uint32_t{p[i]} << 16;
    if (rest == 2) w |= std::uint32_t{p[i + 1]} << 8;
    out.push_back(kAlphabet[(w >> 18) & 63]);
    out.push_back(kAlphabet[(w >> 12) & 63]);
    out.push_back(rest == 2 ? kAlphabet[(w >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

FigureLabel describe_figure(std::string_view key) {
  FigureLabel f;
  for (const KnownKey& k : kKnownKeys)
    if (k.key == key) {
      f.label = k.label;
      f.unit = k.unit;
      f.scale = k.scale;
      f.digits = k.digits;
      f.lower_is_worse = k.lower_is_worse;
      f.timing = f.unit == "s" || f.unit == "ms" || f.unit == "bodies/s";
      return f;
    }
  // The unit suffix.
  std::string_view base = key;
  if (ends_with(base, "_per_s")) {
    base.remove_suffix(6);
    f.unit = "/s";
    f.timing = true;
  } else if (ends_with(base, "_pct")) {
    base.remove_suffix(4);
    f.unit = "%";
  } else if (ends_with(base, "_mm")) {
    base.remove_suffix(3);
    f.unit = "mm";
  } else if (ends_with(base, "_ms") || base == "ms") {
    base.remove_suffix(std::min<std::size_t>(base.size(), 3));
    f.unit = "ms";
    f.timing = true;
  } else if (ends_with(base, "_m")) {
    base.remove_suffix(2);
    f.unit = "mm";
    f.scale = 1000;
  } else if (ends_with(base, "_s")) {
    base.remove_suffix(2);
    f.unit = "s";
    f.timing = true;
  } else if (base.find("strain") != std::string_view::npos) {
    f.unit = "%";  // strains are stored as fractions
    f.scale = 100;
  }
  if (f.unit == "mm" || f.unit == "%" || f.unit == "ms") f.digits = 2;
  // A known phrase at the end, the rest a garment's name.
  for (const KnownPhrase& p : kPhrases) {
    if (base != p.base && !(ends_with(base, p.base) && base[base.size() - p.base.size() - 1] == '_')) continue;
    const std::string_view prefix =
        base == p.base ? std::string_view() : base.substr(0, base.size() - p.base.size() - 1);
    f.label = prefix.empty() ? capitalised(std::string(p.label)) : std::string(prefix) + ": " + std::string(p.label);
    f.digits = p.digits;
    f.lower_is_worse = p.lower_is_worse;
    return f;
  }
  if (base.empty() && f.unit == "ms") {
    f.label = "Time";
    return f;
  }
  // A timing of a garment or template ("top_ms"): "top: time".
  if (f.timing && base.find('_') == std::string_view::npos && !base.empty()) {
    f.label = std::string(base) + ": time";
    return f;
  }
  f.label = capitalised(humanise(base));
  f.lower_is_worse = base.rfind("min_", 0) == 0 || base.find("_min_") != std::string_view::npos;
  return f;
}

std::string format_significant(double v, int digits) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  digits = std::clamp(digits, 1, 17);
  if (v == 0) return "0";
  const double a = std::abs(v);
  if (a < 1e-4 || a >= 1e9) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*e", digits - 1, v);
    return buf;
  }
  int magnitude = static_cast<int>(std::floor(std::log10(a)));
  // Rounding can carry into the next decade (0.0996 to 2 digits is 0.10).
  const int decimals = digits - 1 - magnitude;
  const double rounded = std::round(v * std::pow(10.0, decimals)) / std::pow(10.0, decimals);
  if (rounded != 0 && static_cast<int>(std::floor(std::log10(std::abs(rounded)))) > magnitude) ++magnitude;
  return fixed(v, digits - 1 - magnitude);
}

std::string format_figure(double stored, const FigureLabel& label) {
  const double v = stored * label.scale;
  std::string s = label.scale == 1 && v == std::floor(v) && std::abs(v) < 1e15 ? format_number(v)
                                                                               : format_significant(v, label.digits);
  if (!label.unit.empty()) s += " " + label.unit;
  return s;
}

Histogram histogram(std::span<const double> values, std::size_t bins) {
  Histogram h;
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  if (v.empty()) return h;
  const auto [lo_it, hi_it] = std::minmax_element(v.begin(), v.end());
  const double lo = *lo_it, hi = *hi_it;
  const bool integers = std::all_of(v.begin(), v.end(), [](double x) { return x == std::floor(x); });
  if (integers && hi - lo < 30) {
    for (double e = lo - 0.5; e <= hi + 0.5; e += 1.0) h.edges.push_back(e);
  } else if (hi == lo) {
    h.edges = {lo - 0.5, lo + 0.5};
  } else {
    if (bins == 0)
      bins =
          std::min<std::size_t>(30, static_cast<std::size_t>(std::ceil(std::log2(static_cast<double>(v.size())))) + 1);
    bins = std::max<std::size_t>(bins, 1);
    h.edges.resize(bins + 1);
    // std::lerp: monotonic, exact at both ends, no overflow for a range
    // wider than the largest double (-1e308 to 1e308).
    for (std::size_t i = 0; i <= bins; ++i)
      h.edges[i] = std::lerp(lo, hi, static_cast<double>(i) / static_cast<double>(bins));
  }
  h.counts.assign(h.edges.size() - 1, 0);
  // By comparison with the edges themselves: the rule of the header, exactly.
  for (double x : v) {
    const auto up = std::upper_bound(h.edges.begin(), h.edges.end(), x);
    const auto past = static_cast<std::size_t>(up - h.edges.begin());  // >= 1: edges.front() is the minimum
    const std::size_t i = std::min(std::max<std::size_t>(past, 1), h.counts.size()) - 1;
    ++h.counts[i];
  }
  return h;
}

std::string rows_csv(const json& report) {
  const json& rows = rows_of(report);
  const std::vector<std::string> cols = report_columns(report);
  std::string out;
  for (std::size_t c = 0; c < cols.size(); ++c) out += (c ? "," : "") + csv_field(cols[c]);
  out += "\r\n";
  for (const json& r : rows) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (c) out += ',';
      const auto it = r.find(cols[c]);
      if (it != r.end()) out += csv_field(*it);
    }
    out += "\r\n";
  }
  return out;
}

std::string html_report(const json& report, const HtmlReportOptions& opt) {
  const json& rows = rows_of(report);
  const std::vector<std::string> cols = report_columns(report);
  // What a row is ("bodies"), for the page's sentences and axes.
  const std::string noun = report.contains("row_noun") && report["row_noun"].is_string()
                               ? report["row_noun"].get<std::string>()
                               : std::string("rows");
  const std::string title = report.contains("title") && report["title"].is_string() ? report["title"].get<std::string>()
                                                                                    : std::string("Atelier report");
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>";
  escape_into(h, title);
  h += "</title>\n<style>";
  h += kStyle;
  h += "</style>\n<script>";
  h += kScript;
  h += "</script>\n</head>\n<body>\n<h1>";
  escape_into(h, title);
  h += "</h1>\n";

  if (const auto it = report.find("summary"); it != report.end()) {
    if (!it->is_object()) throw bad("\"summary\" must be an object");
    h += "<h2>Summary</h2>\n<table id=\"summary\"><tbody>\n";
    // Known keys in the table's order (counts, quality, then timings), the
    // others after them in the object's (alphabetical) order.
    std::vector<std::pair<std::size_t, std::string>> order;
    for (const auto& [k, v] : it->items()) {
      std::size_t rank = std::size(kKnownKeys) + order.size();
      for (std::size_t i = 0; i < std::size(kKnownKeys); ++i)
        if (kKnownKeys[i].key == k) rank = i;
      order.emplace_back(rank, k);
    }
    std::sort(order.begin(), order.end());
    for (const auto& [rank, k] : order) {
      const json& v = (*it)[k];
      if (!scalar(v)) throw bad("summary." + k + " is not a scalar");
      const FigureLabel fl = describe_figure(k);
      h += "<tr><th data-key=\"" + escape(k) + "\">" + escape(fl.label) + "</th><td" +
           std::string(v.is_number() ? " class=\"n\"" : "") + ">" +
           (v.is_number() ? escape(format_figure(v.get<double>(), fl)) : cell(v)) + "</td></tr>\n";
    }
    h += "</tbody></table>\n";
  }

  if (!rows.empty() && !opt.csv_name.empty())
    h += "<p>All " + std::to_string(rows.size()) + " " + escape(noun) +
         ", every column at full precision: <a id=\"csv\" href=\"" + escape(opt.csv_name) + "\" download>" +
         escape(opt.csv_name) + "</a> (CSV).</p>\n";

  if (const auto it = report.find("pictures"); it != report.end()) {
    if (!it->is_array()) throw bad("\"pictures\" must be an array");
    h += "<h2>Pictures</h2>\n<div class=\"pics\">\n";
    for (std::size_t i = 0; i < it->size(); ++i) {
      const json& p = (*it)[i];
      if (!p.is_object() || !p.contains("path") || !p["path"].is_string())
        throw bad("pictures[" + std::to_string(i) + "] needs a \"path\" string");
      fs::path path = p["path"].get<std::string>();
      if (path.is_relative() && !opt.picture_dir.empty()) path = opt.picture_dir / path;
      const std::string bytes = io_detail::read_file_bytes(path);
      const RgbImage img = decode_png(bytes, path.string());  // refuses damaged pictures now, not in the browser
      const std::string ptitle =
          p.contains("title") && p["title"].is_string() ? p["title"].get<std::string>() : path.filename().string();
      h += "<figure><img alt=\"" + escape(ptitle) + "\" width=\"" + std::to_string(img.width) + "\" height=\"" +
           std::to_string(img.height) + "\" src=\"data:image/png;base64,";
      h += base64_encode(bytes);
      h += "\"><figcaption><b>" + escape(ptitle) + "</b>";
      if (p.contains("caption") && p["caption"].is_string()) h += "<br>" + escape(p["caption"].get<std::string>());
      if (const auto cb = p.find("colour_bar"); cb != p.end()) {
        const std::string where = "pictures[" + std::to_string(i) + "].colour_bar";
        if (!cb->is_object() || !cb->contains("min") || !cb->contains("max") || !(*cb)["min"].is_number() ||
            !(*cb)["max"].is_number())
          throw bad(where + " needs numbers \"min\" and \"max\"");
        auto map = colour_map_from_name(cb->value("map", std::string("viridis")));
        if (!map) throw bad(where + ": " + map.status().message());
        auto bar = colour_bar(*map, 200, 14);
        if (!bar) throw Error(bar.status());
        const std::string unit = cb->value("unit", std::string());
        auto end = [&](const char* k) {
          std::string t = format_significant((*cb)[k].get<double>(), 2);
          return unit.empty() ? t : t + " " + unit;
        };
        h += "<div class=\"bar\" data-min=\"" + (*cb)["min"].dump() + "\" data-max=\"" + (*cb)["max"].dump() +
             "\"><span class=\"bar-min\">" + escape(end("min")) +
             "</span><img class=\"colour-bar\" alt=\"colour bar: " + escape(std::string(colour_map_name(*map))) +
             "\" width=\"200\" height=\"14\" src=\"data:image/png;base64," + base64_encode(encode_png(*bar)) +
             "\"><span class=\"bar-max\">" + escape(end("max")) + "</span></div>";
        if (cb->contains("label") && (*cb)["label"].is_string())
          h += "<span class=\"bar-label\">" + escape((*cb)["label"].get<std::string>()) + "</span>";
      }
      h += "</figcaption></figure>\n";
    }
    h += "</div>\n";
  }

  const std::vector<ColumnStats> stats = column_statistics(report);
  if (!stats.empty()) {
    h += "<h2>Statistics over " + std::to_string(rows.size()) + " " + escape(noun) +
         "</h2>\n<table id=\"statistics\">\n";
    h += "<thead><tr><th>figure</th><th>count</th><th>min</th><th>mean</th><th>median</th><th>p95</th><th>max</th>"
         "</tr></thead>\n<tbody>\n";
    for (const ColumnStats& s : stats) {
      const FigureLabel fl = describe_figure(s.column);
      h += "<tr><td data-key=\"" + escape(s.column) + "\">" + escape(fl.label) + "</td><td class=\"n\">" +
           std::to_string(s.count) + "</td>";
      for (double v : {s.min, s.mean, s.median, s.p95, s.max})
        h += "<td class=\"n\">" + escape(format_figure(v, fl)) + "</td>";
      h += "</tr>\n";
    }
    h += "</tbody></table>\n";

    // Per-figure histograms (shown units) and the worst rows per figure.
    std::string name_col;
    for (const std::string& c : cols)
      if (std::none_of(stats.begin(), stats.end(), [&](const ColumnStats& st) { return st.column == c; })) {
        name_col = c;
        break;
      }
    h += "<h2>Distributions</h2>\n<div class=\"charts\">\n";
    for (const ColumnStats& st : stats) {
      if (st.min == st.max) continue;  // one value: said in a line below, no chart
      const FigureLabel fl = describe_figure(st.column);
      std::vector<double> shown;
      for (const json& r : rows)
        if (const auto it = r.find(st.column); it != r.end() && it->is_number())
          shown.push_back(it->get<double>() * fl.scale);
      const std::string svg = histogram_svg(st.column, fl, shown, noun);
      if (!svg.empty()) h += "<figure>" + svg + "<figcaption>" + escape(fl.label) + "</figcaption></figure>\n";
    }
    h += "</div>\n<h2>Worst rows per figure</h2>\n<div class=\"worst-tables\">\n";
    for (const ColumnStats& st : stats) {
      const FigureLabel fl = describe_figure(st.column);
      const std::string head = fl.unit.empty() ? fl.label : fl.label + " (" + fl.unit + ")";
      if (st.min == st.max) {
        h += "<p class=\"note\" data-key=\"" + escape(st.column) + "\">" + escape(head) + ": all " +
             std::to_string(st.count) + " " + escape(noun) + " " + escape(format_figure(st.min, fl)) + "</p>\n";
        continue;
      }
      const auto worst = worst_rows(report, st.column, opt.worst_rows, !fl.lower_is_worse);
      h += "<table class=\"worst\" id=\"worst-" + slug(st.column) + "\" data-key=\"" + escape(st.column) +
           "\">\n<caption>" + escape(fl.lower_is_worse ? "lowest " : "highest ") + escape(head) +
           "</caption>\n<thead><tr><th>#</th>";
      if (!name_col.empty()) h += "<th>" + escape(describe_figure(name_col).label) + "</th>";
      h += "<th>" + escape(head) + "</th></tr></thead>\n<tbody>\n";
      for (std::size_t k = 0; k < worst.size(); ++k) {
        const json& r = rows[worst[k]];
        h += "<tr><td class=\"n\">" + std::to_string(k + 1) + "</td>";
        if (!name_col.empty()) {
          const auto it = r.find(name_col);
          h += "<td>" + (it == r.end() ? std::string("&ndash;") : cell(*it)) + "</td>";
        }
        h += "<td class=\"n\">" + escape(format_figure(r[st.column].get<double>(), fl)) + "</td></tr>\n";
      }
      h += "</tbody></table>\n";
    }
    h += "</div>\n";
  }
  h += "<p class=\"note\">Generated by Atelier; self-contained (pictures embedded).</p>\n</body>\n</html>\n";
  return h;
}

void write_html_report(const json& report, const fs::path& path, const HtmlReportOptions& opt) {
  HtmlReportOptions o = opt;
  if (o.picture_dir.empty()) o.picture_dir = path.parent_path();
  const std::string text = html_report(report, o);
  // The CSV first: the page links it.
  if (!rows_of(report).empty() && !o.csv_name.empty()) {
    const std::string csv = rows_csv(report);
    write_atomically(path.parent_path() / o.csv_name, [&](AtomicFile& f) { f.write(csv); });
  }
  write_atomically(path, [&](AtomicFile& f) { f.write(text); });
}

}  // namespace atelier
