#include "regen_job.h"

#include <atelier/engine/status.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/checksum.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <system_error>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error(Status(ErrorCode::kIo, p.string() + ": cannot read"));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string hex32(std::uint32_t v) {
  char b[9];
  std::snprintf(b, sizeof b, "%08x", v);
  return b;
}

/// A file by contents: what matters for the outputs, not where it lies.
nlohmann::json file_identity(const fs::path& p) {
  const std::string bytes = read_bytes(p);
  return {{"file", p.filename().string()}, {"bytes", bytes.size()}, {"crc32", hex32(crc32(bytes))}};
}

std::string absolute_text(const fs::path& p) {
  std::error_code ec;
  const fs::path a = fs::weakly_canonical(p, ec);
  return (ec ? fs::absolute(p) : a).string();
}

/// Every leaf where `was` and `now` differ, as "path: X in the folder, Y now".
void differences(const nlohmann::json& was, const nlohmann::json& now, const std::string& at,
                 std::vector<std::string>& out) {
  if (was.is_object() && now.is_object()) {
    for (const auto& [k, v] : now.items())
      differences(was.contains(k) ? was[k] : nlohmann::json(), v, at.empty() ? k : at + "." + k, out);
    for (const auto& [k, v] : was.items())
      if (!now.contains(k)) differences(v, nlohmann::json(), at.empty() ? k : at + "." + k, out);
    return;
  }
  if (was.is_array() && now.is_array() && was.size() == now.size()) {
    for (std::size_t i = 0; i < now.size(); ++i) differences(was[i], now[i], at + "[" + std::to_string(i) + "]", out);
    return;
  }
  if (was != now)
    out.push_back(at + ": " + (was.is_null() ? "none" : was.dump()) + " in the folder, " +
                  (now.is_null() ? "none" : now.dump()) + " now");
}

bool has_body_records(const fs::path& bodies) {
  std::error_code ec;
  fs::directory_iterator it(bodies, ec), end;
  for (; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".json") return true;
  return false;
}

}  // namespace

nlohmann::json describe_regen_job(const Common& common, const RegenOptions& opt) {
  nlohmann::json src = {{"source", opt.bodies.source}};
  if (opt.bodies.source == "mannequin") {
    src["count"] = opt.bodies.count;
  } else if (opt.bodies.source == "makehuman") {
    src["count"] = opt.bodies.count;
    src["data"] = absolute_text(opt.bodies.data);
    // Issue 26: statures drawn from a survey, bodies on the floor y = 0:
    // other bodies than earlier jobs' of the same seed, so not resumed with them.
    src["bodies"] = "stature-sampled, floor y=0";
  } else {
    // A directory: the folder here, each body file by contents in its own
    // record (body_input_identity: a body set may be large, and an edited
    // body is then computed again instead of refusing the whole folder), the
    // reference by contents.
    src["source"] = absolute_text(opt.bodies.source);
    if (!opt.bodies.reference.empty()) src["reference"] = file_identity(opt.bodies.reference);
    src["scale"] = opt.bodies.scale;
    if (opt.bodies.up != "y") src["up"] = opt.bodies.up;  // absent for Y up: earlier jobs' job.json stays valid
    // The reference's feature curves place profile templates: other curves, another job.
    if (!opt.bodies.features.empty()) src["features"] = file_identity(opt.bodies.features);
  }
  nlohmann::json templates = nlohmann::json::array();
  for (const fs::path& t : opt.templates) templates.push_back(file_identity(t));
  return {{"format", kRegenJobFormat},
          {"tool", "atelier regen"},
          {"seed", common.seed},
          {"bodies", src},
          {"templates", templates},
          {"levels", opt.levels < 0 ? nlohmann::json("each template's") : nlohmann::json(opt.levels)},
          {"clearance", opt.clearance < 0 ? nlohmann::json("each template's") : nlohmann::json(opt.clearance)},
          {"meshes", opt.meshes}};
}

std::string claim_regen_folder(const fs::path& out, const nlohmann::json& job, bool no_resume, bool writer) {
  const fs::path file = out / "job.json";
  std::error_code ec;
  if (no_resume) {
    if (writer) fs::remove(file, ec);
    return {};
  }
  const std::string again = " (rerun with --no-resume to recompute every body, or choose another --out)";
  // Records first: rank 0 writes job.json before any record, so another rank
  // that sees a record then sees job.json.
  const bool records = has_body_records(out / "bodies");
  if (fs::exists(file, ec)) {
    const nlohmann::json was = nlohmann::json::parse(read_bytes(file), nullptr, false);
    if (was.is_discarded()) return file.string() + ": not valid JSON, so the folder's records are not trusted" + again;
    std::vector<std::string> diff;
    differences(was, job, "", diff);
    if (diff.empty()) return {};
    std::string why = out.string() + " holds the outputs of another job:";
    for (const std::string& d : diff) why += "\n  " + d;
    return why + "\n" + again.substr(2, again.size() - 3);
  }
  if (records)
    return out.string() +
           " holds body records but no job.json (written by an older atelier, or its --no-resume run was "
           "interrupted), so they may belong to another job" +
           again;
  if (writer) record_regen_job(out, job);
  return {};
}

void record_regen_job(const fs::path& out, const nlohmann::json& job) {
  write_atomically(out / "job.json", [&](AtomicFile& f) { f.write(job.dump(1)); });
}

nlohmann::json body_input_identity(const fs::path& file) {
  if (file.empty()) return nullptr;
  try {
    return file_identity(file);
  } catch (const Error&) {
    return nullptr;  // unreadable: the body is computed, and its failure recorded
  }
}

bool body_record_complete(const fs::path& record, bool patterns, const nlohmann::json& input) {
  std::ifstream in(record, std::ios::binary);
  if (!in) return false;
  const nlohmann::json r = nlohmann::json::parse(in, nullptr, false);
  return !r.is_discarded() && r.is_object() && r.contains("ok") && r["ok"] == true &&
         (!patterns || r.contains("patterns")) && (input.is_null() || (r.contains("input") && r["input"] == input));
}

void require_finite(const std::string& name, const std::vector<Vec3d>& positions,
                    std::initializer_list<std::pair<const char*, double>> figures, const Model* model) {
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (model && !model->alive(NodeIdx{static_cast<std::uint32_t>(v)})) continue;
    if (!positions[v].allFinite())
      throw Error(Status(ErrorCode::kDegenerate,
                         name + ": regenerated node " + std::to_string(v) + " has a non-finite position"));
  }
  for (const auto& [figure, value] : figures)
    if (!std::isfinite(value))
      throw Error(Status(ErrorCode::kDegenerate, name + ": quality figure " + figure + " is not finite"));
}

}  // namespace atelier::cli
