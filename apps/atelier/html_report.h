// A self-contained HTML report (issue #6): pictures embedded as base64 PNG
// data URIs, a summary table, per-column statistics and the per-body table,
// with no external resource (no fonts, styles, scripts or images fetched).
//
// Input: a JSON object of this generic shape (every key but "rows" optional):
//
//   {
//     "title":    "Garment regeneration on 100 bodies",
//     "summary":  {"bodies": 100, "failed": 0, "method": "detail template"},
//     "columns":  ["name", "max_penetration_mm", "mean_offset_mm"],
//     "rows":     [{"name": "body_0000", "max_penetration_mm": 0.3, ...}, ...],
//     "pictures": [{"title": "body_0000 front", "path": "body_0000_front.png",
//                   "caption": "worst max_penetration_mm"}, ...]
//   }
//
// "summary" values are scalars (number, string, bool, null). "rows" are
// objects of scalars; "columns" fixes the column order (default: the union of
// the rows' keys, each row's in nlohmann::json's order, i.e. alphabetical). Statistics (count, min, mean, median,
// 95th percentile, max) are computed for every column whose non-null values
// are all numbers. Picture paths are relative to a base directory (default:
// the report's directory) or absolute; each must be a readable PNG.
//
// The page carries a short inline script that, once every image has decoded
// (naturalWidth > 0), sets data-images-decoded="<count>" on <body> (or
// "failed"): a headless browser check reads it back from the dumped DOM.
//
// Malformed input throws Error(kInvalidArgument) naming the offending key;
// missing or damaged pictures throw Error(kIo)/Error(kParse) naming the path.
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace atelier {

struct ColumnStats {
  std::string column;
  std::size_t count = 0;  // numeric values (nulls are skipped)
  double min = 0, mean = 0, median = 0, p95 = 0, max = 0;
};

/// Column names: report["columns"], or the union of the rows' keys (sorted
/// within a row, as nlohmann::json stores them) in order of first appearance.
[[nodiscard]] std::vector<std::string> report_columns(const nlohmann::json& report);

/// Statistics of every numeric column (order of report_columns). Percentiles
/// interpolate linearly between order statistics (type 7 of Hyndman & Fan).
[[nodiscard]] std::vector<ColumnStats> column_statistics(const nlohmann::json& report);

/// Indices of the k rows with the largest (or smallest) numeric value in
/// `column`, worst first; ties go to the lower row index; rows without a
/// number there are skipped. For choosing which bodies to picture.
[[nodiscard]] std::vector<std::size_t> worst_rows(const nlohmann::json& report, std::string_view column,
                                                  std::size_t k, bool largest = true);

/// Standard base64 (RFC 4648, with padding).
[[nodiscard]] std::string base64_encode(std::string_view bytes);

struct HtmlReportOptions {
  /// Rows shown in the per-body table (statistics always use every row).
  std::size_t max_rows = 2000;
  /// Base directory of relative picture paths; empty = the report's folder.
  std::filesystem::path picture_dir;
};

/// The HTML text. Relative picture paths resolve against opt.picture_dir
/// (current directory when empty).
[[nodiscard]] std::string html_report(const nlohmann::json& report, const HtmlReportOptions& opt = {});
/// html_report() written atomically to `path`.
void write_html_report(const nlohmann::json& report, const std::filesystem::path& path,
                       const HtmlReportOptions& opt = {});

}  // namespace atelier
