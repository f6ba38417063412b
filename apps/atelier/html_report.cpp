#include "html_report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>
#include <unordered_set>

#include <atelier/engine/status.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/mesh_arrays.h>
#include <atelier/io/png.h>

namespace atelier {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Error bad(std::string_view what) { return Error(Status(ErrorCode::kInvalidArgument, "html report: " + std::string(what))); }

void escape_into(std::string& out, std::string_view s) {
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out.push_back(c);
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

bool scalar(const json& v) { return v.is_null() || v.is_number() || v.is_string() || v.is_boolean(); }

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
  std::stable_sort(v.begin(), v.end(), [&](const auto& a, const auto& b) {
    return largest ? a.first > b.first : a.first < b.first;
  });
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

std::string html_report(const json& report, const HtmlReportOptions& opt) {
  const json& rows = rows_of(report);
  const std::vector<std::string> cols = report_columns(report);
  const std::string title = report.contains("title") && report["title"].is_string()
                                ? report["title"].get<std::string>()
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
    for (const auto& [k, v] : it->items()) {
      if (!scalar(v)) throw bad("summary." + k + " is not a scalar");
      h += "<tr><th>" + escape(k) + "</th><td" + std::string(v.is_number() ? " class=\"n\"" : "") + ">" + cell(v) +
           "</td></tr>\n";
    }
    h += "</tbody></table>\n";
  }

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
      const std::string ptitle = p.contains("title") && p["title"].is_string() ? p["title"].get<std::string>()
                                                                               : path.filename().string();
      h += "<figure><img alt=\"" + escape(ptitle) + "\" width=\"" + std::to_string(img.width) + "\" height=\"" +
           std::to_string(img.height) + "\" src=\"data:image/png;base64,";
      h += base64_encode(bytes);
      h += "\"><figcaption><b>" + escape(ptitle) + "</b>";
      if (p.contains("caption") && p["caption"].is_string()) h += "<br>" + escape(p["caption"].get<std::string>());
      h += "</figcaption></figure>\n";
    }
    h += "</div>\n";
  }

  const std::vector<ColumnStats> stats = column_statistics(report);
  if (!stats.empty()) {
    h += "<h2>Statistics over " + std::to_string(rows.size()) + " rows</h2>\n<table id=\"statistics\">\n";
    h += "<thead><tr><th>column</th><th>count</th><th>min</th><th>mean</th><th>median</th><th>p95</th><th>max</th>"
         "</tr></thead>\n<tbody>\n";
    for (const ColumnStats& s : stats) {
      h += "<tr><td>" + escape(s.column) + "</td><td class=\"n\">" + std::to_string(s.count) + "</td>";
      for (double v : {s.min, s.mean, s.median, s.p95, s.max}) h += "<td class=\"n\">" + format_number(v) + "</td>";
      h += "</tr>\n";
    }
    h += "</tbody></table>\n";
  }

  if (!rows.empty()) {
    const std::size_t shown = std::min(rows.size(), opt.max_rows);
    h += "<h2>Rows</h2>\n";
    if (shown < rows.size())
      h += "<p class=\"note\">First " + std::to_string(shown) + " of " + std::to_string(rows.size()) +
           " rows (statistics use all).</p>\n";
    h += "<table id=\"rows\">\n<thead><tr>";
    for (const std::string& c : cols) h += "<th>" + escape(c) + "</th>";
    h += "</tr></thead>\n<tbody>\n";
    for (std::size_t i = 0; i < shown; ++i) {
      h += "<tr>";
      for (const std::string& c : cols) {
        const auto it = rows[i].find(c);
        const bool num = it != rows[i].end() && it->is_number();
        h += num ? "<td class=\"n\">" : "<td>";
        h += it == rows[i].end() ? std::string("&ndash;") : cell(*it);
        h += "</td>";
      }
      h += "</tr>\n";
    }
    h += "</tbody></table>\n";
  }
  h += "<p class=\"note\">Generated by Atelier; self-contained (pictures embedded).</p>\n</body>\n</html>\n";
  return h;
}

void write_html_report(const json& report, const fs::path& path, const HtmlReportOptions& opt) {
  HtmlReportOptions o = opt;
  if (o.picture_dir.empty()) o.picture_dir = path.parent_path();
  const std::string text = html_report(report, o);
  write_atomically(path, [&](AtomicFile& f) { f.write(text); });
}

}  // namespace atelier
