#include "systems/makehuman_body.h"

#include <algorithm>
#include <stdexcept>

#include "engine/parallel.h"
#include "engine/random.h"
#include "engine/status.h"

namespace atelier::makehuman {

namespace {

struct AgeFactors {
  double child, young, old;
};

AgeFactors age_factors(double a) {
  // README: for a < 0.5, young = max(0, (a - 0.1875) * 3.2), child = max(0,
  // min(1, 5.333 a) - young), old = 0; for a >= 0.5, old = 2a - 1, young = 1 - old.
  if (a < 0.5) {
    const double young = std::max(0.0, (a - 0.1875) * 3.2);
    const double child = std::max(0.0, std::min(1.0, 5.333 * a) - young);
    return {child, young, 0.0};
  }
  const double old = 2 * a - 1;
  return {0.0, 1 - old, old};
}

double ethnic_share(double v, const MacroParams& p) {
  const double sum = p.african + p.asian + p.caucasian;
  return sum > 0 ? v / sum : 1.0 / 3.0;
}

// min/average/max split of a [0,1] slider (muscle, weight).
double three_way(std::string_view level, double v) {
  const double mx = std::max(0.0, 2 * v - 1), mn = std::max(0.0, 1 - 2 * v);
  if (level == "max") return mx;
  if (level == "min") return mn;
  return 1 - mx - mn;
}

}  // namespace

double macro_factor(std::string_view t, const MacroParams& p) {
  if (t == "universal") return 1.0;
  if (t == "male") return p.gender;
  if (t == "female") return 1 - p.gender;
  if (t == "child") return age_factors(p.age).child;
  if (t == "young") return age_factors(p.age).young;
  if (t == "old") return age_factors(p.age).old;
  if (t == "african") return ethnic_share(p.african, p);
  if (t == "asian") return ethnic_share(p.asian, p);
  if (t == "caucasian") return ethnic_share(p.caucasian, p);
  for (std::string_view lvl : {"min", "average", "max"}) {
    if (t.size() > lvl.size() && t.substr(0, lvl.size()) == lvl) {
      const std::string_view what = t.substr(lvl.size());
      if (what == "muscle") return three_way(lvl, p.muscle);
      if (what == "weight") return three_way(lvl, p.weight);
      if (what == "height" && lvl != "average") return lvl == "max" ? std::max(0.0, 2 * p.height - 1)
                                                                     : std::max(0.0, 1 - 2 * p.height);
    }
  }
  if (t == "idealproportions") return std::max(0.0, 2 * p.proportions - 1);
  if (t == "uncommonproportions") return std::max(0.0, 1 - 2 * p.proportions);
  throw std::invalid_argument("unknown macro factor '" + std::string(t) + "'");
}

double macro_target_weight(std::string_view name, const MacroParams& p) {
  // Strip a folder prefix ("height/") and the extension.
  if (auto s = name.rfind('/'); s != std::string_view::npos) name = name.substr(s + 1);
  if (name.size() > 7 && name.substr(name.size() - 7) == ".target") name = name.substr(0, name.size() - 7);
  double w = 1.0;
  std::size_t pos = 0;
  while (pos <= name.size()) {
    std::size_t dash = name.find('-', pos);
    if (dash == std::string_view::npos) dash = name.size();
    w *= macro_factor(name.substr(pos, dash - pos), p);
    pos = dash + 1;
  }
  return w;
}

std::vector<MacroParams> sample_adults(std::size_t n, std::uint64_t seed) {
  std::vector<MacroParams> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    SplitMix64 r(stream_seed(seed, i));
    MacroParams& p = out[i];
    // Gender: mostly clearly male or female, some androgynous mixes.
    const bool male = r.uniform() < 0.5;
    const double spread = r.uniform(0.0, 0.25);
    p.gender = male ? 1.0 - spread : spread;
    p.age = r.uniform(0.45, 0.95);
    p.weight = r.uniform(0.1, 0.9);
    p.height = r.uniform(0.2, 0.9);
    p.muscle = r.uniform(0.3, 0.8);
    p.proportions = r.uniform(0.3, 0.9);
    // Mixed ethnicity: a dominant one with random admixture.
    double e[3] = {r.uniform(0.05, 1.0), r.uniform(0.05, 1.0), r.uniform(0.05, 1.0)};
    e[r.next() % 3] += 1.0;
    const double s = e[0] + e[1] + e[2];
    p.african = e[0] / s;
    p.asian = e[1] / s;
    p.caucasian = e[2] / s;
  }
  return out;
}

HumanLibrary HumanLibrary::load(const std::filesystem::path& dir, const ExecContext& ctx) {
  namespace fs = std::filesystem;
  HumanLibrary lib;
  if (!fs::is_directory(dir)) throw Error(Status(ErrorCode::kIo, dir.string() + ": not a MakeHuman data folder"));
  lib.base_ = read_base_mesh(dir / "base.obj");
  const auto nv = lib.vertex_count();
  std::vector<fs::path> macro_files, measure_files;
  const fs::path macro_dir = dir / "targets" / "macrodetails";
  for (const auto& e : fs::recursive_directory_iterator(macro_dir))
    if (e.is_regular_file() && e.path().extension() == ".target") macro_files.push_back(e.path());
  for (const auto& e : fs::directory_iterator(dir / "targets" / "measure"))
    if (e.is_regular_file() && e.path().extension() == ".target") measure_files.push_back(e.path());
  std::sort(macro_files.begin(), macro_files.end());
  std::sort(measure_files.begin(), measure_files.end());
  auto load_all = [&](const std::vector<fs::path>& files, std::vector<Target>& out) {
    out.resize(files.size());
    std::vector<std::string> errors(files.size());
    ExecContext c = ctx;
    c.sequential_threshold = 2;
    c.grain = 1;
    par::for_each_n(c, files.size(), [&](std::size_t i) {
      try {
        out[i] = read_target(files[i], nv);
      } catch (const Error& e) {
        errors[i] = e.what();
      }
    });
    for (const auto& e : errors)
      if (!e.empty()) throw Error(Status(ErrorCode::kParse, e));
    std::sort(out.begin(), out.end(), [](const Target& a, const Target& b) { return a.name < b.name; });
  };
  load_all(macro_files, lib.macro_);
  load_all(measure_files, lib.measure_);
  // Check every macro name parses now, not at build time.
  MacroParams probe;
  for (const auto& t : lib.macro_) (void)macro_target_weight(t.name, probe);
  return lib;
}

const Target* HumanLibrary::find_target(std::string_view name) const noexcept {
  for (const auto* list : {&macro_, &measure_})
    for (const auto& t : *list)
      if (t.name == name) return &t;
  return nullptr;
}

std::vector<std::pair<const Target*, double>> HumanLibrary::active_targets(const MacroParams& p) const {
  std::vector<std::pair<const Target*, double>> out;
  for (const auto& t : macro_) {
    const double w = macro_target_weight(t.name, p);
    if (w > 0) out.emplace_back(&t, w);
  }
  for (const auto& [name, v] : p.measures) {
    if (v == 0) continue;
    const std::string side = name + (v < 0 ? "-decr" : "-incr");
    const Target* t = nullptr;
    for (const auto& m : measure_)
      if (m.name == side) t = &m;
    if (!t) throw std::invalid_argument("unknown measure modifier '" + name + "'");
    out.emplace_back(t, std::abs(v));
  }
  return out;
}

void HumanLibrary::build(const MacroParams& p, std::span<Vec3f> out) const {
  if (out.size() != base_.positions.size())
    throw std::invalid_argument("HumanLibrary::build: output has the wrong vertex count");
  std::copy(base_.positions.begin(), base_.positions.end(), out.begin());
  // Fixed target order and float accumulation in that order: deterministic.
  for (const auto& [t, w] : active_targets(p)) {
    const float wf = static_cast<float>(w);
    for (std::size_t k = 0; k < t->index.size(); ++k) out[t->index[k]] += wf * t->delta[k];
  }
}

}  // namespace atelier::makehuman
