#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>

#include "commands.h"
#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/measure.h>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

}  // namespace

void check_mesh_output(const fs::path& p) {
  const std::string e = lower_ext(p);
  if (e != ".obj" && e != ".ply" && e != ".off" && e != ".atm")
    throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": unknown format (use .obj, .ply, .off or .atm)"));
}

void write_mesh_file(const Model& m, const fs::path& p, const Log& log) {
  const std::string e = lower_ext(p);
  if (e == ".obj") return write_obj(m, p);
  if (e == ".ply") return write_ply(m, p, true);
  if (e == ".off") {
    // OFF has one mesh: say so instead of merging the surfaces silently.
    if (const std::size_t merged = write_off(m, p); merged > 1)
      log.warn(p.string() + ": OFF keeps no surfaces: " + std::to_string(merged) +
               " surfaces merged into one mesh (write .ply, .obj or .atm to keep them)");
    return;
  }
  if (e == ".atm") return write_model(m, p);
  throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": unknown format (use .obj, .ply, .off or .atm)"));
}

Model read_mesh_file(const fs::path& p) {
  if (!fs::exists(p)) throw Error(Status(ErrorCode::kIo, p.string() + ": no such file"));
  const std::string e = lower_ext(p);
  if (e == ".obj") return read_obj(p);
  if (e == ".ply") return read_ply(p);
  if (e == ".off") return read_off(p);
  if (e == ".atm") return read_model(p);
  throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": unknown format (use .obj, .ply, .off or .atm)"));
}

int run_validate(const Common&, const fs::path& file, Log& log) {
  const Model m = read_mesh_file(file);
  const TopologyCounts t = count_topology(m);
  std::printf("%s: %zu surfaces, V=%lld E=%lld F=%lld, components %lld, closed shells %lld, complex holes %lld\n",
              file.string().c_str(), m.num_surfaces(), static_cast<long long>(t.nodes),
              static_cast<long long>(t.edges), static_cast<long long>(t.faces),
              static_cast<long long>(t.components), static_cast<long long>(t.shells),
              static_cast<long long>(m.complex_holes));
  const Status s = validate(m);
  if (!s) {
    log.error(file.string() + ": " + s.message());
    return kExitPartial;
  }
  std::printf("valid\n");
  return kExitOk;
}

int run_convert(const Common&, const fs::path& in, const fs::path& out, Log& log) {
  const Model m = read_mesh_file(in);
  write_mesh_file(m, out, log);
  log.info("wrote " + out.string());
  return kExitOk;
}

BodyFrame body_frame(double scale, const std::string& up) {
  auto axis = parse_up_axis(up);
  if (!axis) throw Error(Status(ErrorCode::kInvalidArgument, "--up " + axis.status().message()));
  const BodyFrame frame{scale, *axis};
  if (Status s = frame.check(); !s) throw Error(Status(s.code(), "--scale: " + s.message()));
  return frame;
}

CLI::Validator body_count_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        // Parsed here as a signed number: CLI11 would wrap "-1" into 2^64-1.
        long double v = 0;
        std::istringstream in(text);
        if (!(in >> v) || !(in >> std::ws).eof() || v != std::floor(v))
          return "'" + text + "' is not a whole number of bodies";
        if (v < 1 || v > static_cast<long double>(kMaxBodyCount))
          return "'" + text + "' bodies: a count is from 1 to " + std::to_string(kMaxBodyCount);
        return {};
      },
      "COUNT");
}

std::string unknown_subcommand(const CLI::App& app, int argc, const char* const* argv) {
  if (!app.get_subcommands().empty()) return {};  // a subcommand was recognised: its own error
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--threads" || a == "--seed") {
      ++i;  // their value
      continue;
    }
    if (a.empty() || a[0] == '-') continue;
    std::string known;
    for (const CLI::App* sub : app.get_subcommands({})) {
      if (sub->get_name() == a) return {};
      known += (known.empty() ? "" : ", ") + sub->get_name();
    }
    return "atelier: unknown subcommand '" + std::string(a) + "'; the subcommands are: " + known +
           " (atelier --help)";
  }
  return {};
}

CLI::Validator clearance_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        std::istringstream in(text);
        if (!(in >> v) || !(in >> std::ws).eof() || !std::isfinite(v) || v < 0 || v > kMaxClearance) {
          std::ostringstream m;
          m << "clearance '" << text << "': a distance in metres from 0 to " << kMaxClearance;
          return m.str();
        }
        return {};
      },
      "METRES");
}

void make_output_dir(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  fs::create_directories(dir, ec);
  if (!ec && fs::is_directory(dir)) return;
  // Name what is in the way: the nearest existing part of the path that is not a folder.
  for (fs::path p = dir; !p.empty() && p != p.parent_path(); p = p.parent_path()) {
    std::error_code e2;
    const auto st = fs::status(p, e2);
    if (fs::exists(st) && !fs::is_directory(st))
      throw Error(Status(ErrorCode::kIo, dir.string() + ": cannot create the output folder: " + p.string() +
                                             " is a file, not a folder"));
  }
  throw Error(Status(ErrorCode::kIo, dir.string() + ": cannot create the output folder: " +
                                         (ec ? ec.message() : std::string("not a folder"))));
}

std::size_t remove_stale_output_temporaries(const fs::path& out) noexcept {
  std::size_t n = remove_stale_temporaries(out);
  std::error_code ec;
  // Symlinks are not followed: only what this command wrote is visited.
  fs::recursive_directory_iterator it(out, fs::directory_options::skip_permission_denied, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    if (it->is_directory(e2) && !it->is_symlink(e2)) n += remove_stale_temporaries(it->path());
  }
  return n;
}

std::unique_ptr<BodySource> make_body_source(const Common& common, const BodiesOptions& opt) {
  const ExecContext ctx = common.context();
  std::unique_ptr<BodySource> src;
  if (!opt.features.empty() && (opt.source == "mannequin" || opt.source == "makehuman"))
    throw Error(Status(ErrorCode::kInvalidArgument, "--features is for a directory source's --reference body OBJ; the " +
                                                        opt.source + " has its own feature curves"));
  if (opt.source == "mannequin") {
    auto topo = make_mannequin_topology();
    if (!topo) throw Error(topo.status());
    auto t = std::make_shared<const MannequinTopology>(std::move(*topo));
    auto ref = make_mannequin(MannequinParams{}, *t);
    if (!ref) throw Error(ref.status());
    src = std::make_unique<MannequinSource>(t, opt.count, common.seed,
                                            std::make_shared<const ReferenceBody>(std::move(*ref)));
  } else if (opt.source == "makehuman") {
    auto lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(opt.data / "makehuman", ctx));
    auto ref = std::make_shared<const ReferenceBody>(makehuman::make_reference_body(*lib));
    src = std::make_unique<makehuman::MakeHumanSource>(lib, opt.count, common.seed, ref);
  } else {
    // Not a directory: a misspelt source name, which "--reference is
    // required" would only hide.
    if (!fs::is_directory(opt.source))
      throw Error(Status(ErrorCode::kInvalidArgument, "--source '" + opt.source +
                                                          "': neither mannequin, makehuman nor a directory of OBJ bodies"));
    if (opt.reference.empty())
      throw Error(Status(ErrorCode::kInvalidArgument, "--reference is required with a directory source"));
    const BodyFrame frame = body_frame(opt.scale, opt.up);
    auto ref = read_reference_body(opt.reference, {.frame = frame, .makehuman_data = opt.data, .features = opt.features},
                                   ctx);
    if (!ref) throw Error(ref.status());
    src = std::make_unique<ObjDirectorySource>(opt.source, std::make_shared<const ReferenceBody>(std::move(*ref)),
                                               frame);
  }
  return src;
}

int run_bodies(const Common& common, const BodiesOptions& opt, Log& log) {
  const ExecContext ctx = common.context();
  std::unique_ptr<BodySource> src = make_body_source(common, opt);
  make_output_dir(opt.out);
  const auto ref = src->reference();
  BodySet chunk(ref);
  std::vector<BodyFailure> failures;
  std::size_t written = 0;
  const std::size_t n = src->size();
  write_atomically(opt.out / "measurements.csv", [&](AtomicFile& f) {
    std::size_t done = 0;
    for (std::size_t first = 0; first < n; first += 64) {
      src->generate(first, 64, chunk, failures, ctx);
      if (first == 0) {
        // What each body was made from beside what is measured on it; the
        // headless mannequin's vertical extent is the form's, not a stature.
        std::string header = "body";
        for (const auto& [name, v] : src->parameters(0)) header += "," + name;
        for (const std::string& c : measurement_columns(*ref))
          header += "," + (c == "stature" && !src->whole_person() ? std::string("form_height") : c);
        f.write(header + "\n");
      }
      std::ostringstream rows;
      Status s = measurements_csv(
          rows, *ref, chunk.size(), [&](std::size_t i) { return chunk.positions(i); }, ctx, false, first);
      if (!s) throw Error(s);
      std::istringstream lines(rows.str());
      std::size_t b = 0;
      for (std::string line; std::getline(lines, line); ++b) {
        std::size_t index = first + b;  // the body's index in the source, by name (a failed body is skipped)
        for (std::size_t i = first; i < std::min(n, first + 64); ++i)
          if (b < chunk.size() && src->body_name(i) == chunk.name(b)) index = i;
        const std::size_t comma = line.find(',');
        std::string params;
        for (const auto& [name, v] : src->parameters(index)) params += "," + v;
        f.write(line.substr(0, comma) + params + line.substr(comma) + "\n");
      }
      for (std::size_t b = 0; b < chunk.size() && written < opt.meshes; ++b, ++written) {
        Model m = ref->model;
        chunk.positions(b, m.nodes.position);
        src->frame().to_file(m.nodes.position);  // back in the files' units and axes
        write_obj(m, opt.out / (chunk.name(b) + ".obj"));
      }
      done += chunk.size();
      log.progress("bodies", std::min(n, first + 64), n);
    }
    log.end_progress();
  });
  remove_stale_output_temporaries(opt.out);  // a killed earlier run's
  for (const auto& fl : failures) log.warn(fl.name + ": " + fl.status.message());
  std::printf("%zu bodies, %zu failed; measurements in %s\n", n, failures.size(),
              (opt.out / "measurements.csv").string().c_str());
  return failures.empty() ? kExitOk : kExitPartial;
}

}  // namespace atelier::cli
