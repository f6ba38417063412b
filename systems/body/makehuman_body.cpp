// MakeHuman bodies (makehuman_body.h): the macro sliders' weights, the
// adult sampler, the library's loading, building a body, and the reference
// body with its feature curves.
// Why this file is long: these share HumanLibrary's private tables (the
// targets, their factor indices, the stature candidates and the targets'
// chunked form), and splitting them would put those tables in a detail
// header for no reader's gain.
#include <atelier/systems/body/makehuman_body.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <atelier/engine/parallel.h>
#include <atelier/engine/random.h>
#include <atelier/engine/status.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/mesh/section.h>

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

// Every factor token of the macro target names, and its index.
constexpr std::array<std::string_view, 19> kFactorNames = {
    "universal",     "male",          "female",    "child",         "young",         "old",
    "african",       "asian",         "caucasian", "minmuscle",     "averagemuscle", "maxmuscle",
    "minweight",     "averageweight", "maxweight", "minheight",     "maxheight",     "idealproportions",
    "uncommonproportions"};

std::string_view target_stem(std::string_view name) {
  if (auto s = name.rfind('/'); s != std::string_view::npos) name = name.substr(s + 1);
  if (name.size() > 7 && name.substr(name.size() - 7) == ".target") name = name.substr(0, name.size() - 7);
  return name;
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
  name = target_stem(name);
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
  std::vector<MacroParams> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(sample_adult(seed, i));
  return out;
}

MacroParams sample_adult(std::uint64_t seed, std::size_t index) {
  MacroParams p;
  {
    SplitMix64 r(stream_seed(seed, index));
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
  return p;
}

namespace {

// out[16 c + l] += w * value[16 i + l] for the lanes l of mask[i], c =
// chunk[i]: masked loads and stores (no lane outside the mask is touched,
// so the last chunk may pass the end of out) and no fused multiply-add, so
// each coordinate is rounded as in the scalar loop.
__attribute__((target("avx512f"), optimize("fp-contract=off"))) void add_chunks_avx512(
    float* out, const std::uint32_t* chunk, const std::uint16_t* mask, const float* value, std::size_t n, float w) {
  const __m512 wf = _mm512_set1_ps(w);
  for (std::size_t i = 0; i < n; ++i) {
    float* o = out + 16 * static_cast<std::size_t>(chunk[i]);
    const __mmask16 m = mask[i];
    const __m512 cur = _mm512_maskz_loadu_ps(m, o);
    _mm512_mask_storeu_ps(o, m, _mm512_add_ps(cur, _mm512_mul_ps(wf, _mm512_loadu_ps(value + 16 * i))));
  }
}

}  // namespace

HumanLibrary::ChunkTarget HumanLibrary::chunk_target(const Target& t) {
  ChunkTarget out;
  std::vector<std::pair<std::uint32_t, std::uint32_t>>
      coord;  // (interleaved coordinate, displacement index * 3 + axis)
  coord.reserve(3 * t.index.size());
  for (std::size_t k = 0; k < t.index.size(); ++k)
    for (std::uint32_t a = 0; a < 3; ++a) coord.emplace_back(3 * t.index[k] + a, static_cast<std::uint32_t>(3 * k + a));
  // Targets list their vertices in increasing order (then this is sorted
  // already); any other order is sorted here.
  if (!std::is_sorted(coord.begin(), coord.end())) std::sort(coord.begin(), coord.end());
  for (std::size_t q = 0; q < coord.size(); ++q) {
    if (q > 0 && coord[q].first == coord[q - 1].first) return {};
    const std::uint32_t ch = coord[q].first / 16, lane = coord[q].first % 16;
    if (out.chunk.empty() || out.chunk.back() != ch) {
      out.chunk.push_back(ch);
      out.mask.push_back(0);
      out.value.resize(out.value.size() + 16, 0.0f);
    }
    out.mask.back() = static_cast<std::uint16_t>(out.mask.back() | (1u << lane));
    out.value[16 * (out.chunk.size() - 1) + lane] = t.delta[coord[q].second / 3][coord[q].second % 3];
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
  if (fs::exists(dir / "measures.json")) lib.measures_ = read_measures(dir / "measures.json", nv);
  // The measure sliders MakeHuman declares, each two-sided (min "decr", max "incr").
  const fs::path mods = dir / "modifiers" / "measurement_modifiers.json";
  if (fs::exists(mods)) {
    for (const MeasureModifier& m : read_measure_modifiers(mods)) {
      for (const std::string* side : {&m.min, &m.max})
        if (!lib.find_target(m.target + "-" + *side))
          throw Error(Status(ErrorCode::kParse, mods.string() + ": modifier '" + m.target + "' has no " + *side +
                                                    " target in targets/measure"));
      lib.measure_modifiers_.push_back(m.target);
    }
  }
  if (const auto* body = lib.base_.group("body")) {
    for (auto v : body->face_nodes) lib.skin_vertices_ = std::max(lib.skin_vertices_, v + 1);
  } else {
    throw Error(Status(ErrorCode::kParse, (dir / "base.obj").string() + ": no 'body' group"));
  }
  // Check every macro name parses now, not at build time, and keep its
  // factors' indices.
  MacroParams probe;
  for (const auto& t : lib.macro_) {
    (void)macro_target_weight(t.name, probe);
    const std::string_view name = target_stem(t.name);
    auto& f = lib.macro_factors_.emplace_back();
    std::size_t pos = 0;
    while (pos <= name.size()) {
      std::size_t dash = name.find('-', pos);
      if (dash == std::string_view::npos) dash = name.size();
      const auto it = std::find(kFactorNames.begin(), kFactorNames.end(), name.substr(pos, dash - pos));
      if (it == kFactorNames.end())
        throw Error(Status(ErrorCode::kParse, t.name + ": unknown macro factor '" +
                                                  std::string(name.substr(pos, dash - pos)) + "'"));
      f.push_back(static_cast<std::uint8_t>(it - kFactorNames.begin()));
      pos = dash + 1;
    }
  }
  // Stature candidates: skin vertices within 4% of the base body's height
  // of its top or its bottom (the head's crown, the soles).
  {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (std::uint32_t v = 0; v < lib.skin_vertices_; ++v) {
      lo = std::min(lo, lib.base_.positions[v].y());
      hi = std::max(hi, lib.base_.positions[v].y());
    }
    const float band = 0.04f * (hi - lo);
    std::vector<std::int64_t> slot(nv, -1);
    for (std::uint32_t v = 0; v < lib.skin_vertices_; ++v) {
      const float y = lib.base_.positions[v].y();
      if (y > lo + band && y < hi - band) continue;
      slot[v] = static_cast<std::int64_t>(lib.stature_vertices_.size());
      lib.stature_vertices_.push_back(v);
      lib.stature_base_y_.push_back(y);
    }
    for (const auto* list : {&lib.macro_, &lib.measure_})
      for (const Target& t : *list) {
        auto& dy = lib.stature_dy_.emplace_back();
        for (std::size_t k = 0; k < t.index.size(); ++k)
          if (slot[t.index[k]] >= 0) dy.emplace_back(static_cast<std::uint32_t>(slot[t.index[k]]), t.delta[k].y());
      }
  }
  // The chunked form of every target, for build().
  lib.chunks_.resize(lib.macro_.size() + lib.measure_.size());
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, lib.chunks_.size(), [&](std::size_t k) {
    const Target& t = k < lib.macro_.size() ? lib.macro_[k] : lib.measure_[k - lib.macro_.size()];
    lib.chunks_[k] = chunk_target(t);
  });
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
  // Each factor once, then each target's product in its name's order (the
  // value macro_target_weight gives, bit for bit).
  std::array<double, kFactorNames.size()> factor{};
  for (std::size_t k = 0; k < kFactorNames.size(); ++k) factor[k] = macro_factor(kFactorNames[k], p);
  for (std::size_t i = 0; i < macro_.size(); ++i) {
    double w = 1.0;
    for (std::uint8_t k : macro_factors_[i]) w *= factor[k];
    if (w > 0) out.emplace_back(&macro_[i], w);
  }
  for (const auto& [name, v] : p.measures) {
    if (v == 0) continue;
    const std::string side = name + (v < 0 ? "-decr" : "-incr");
    const Target* t = nullptr;
    for (const auto& m : measure_)
      if (m.name == side) t = &m;
    if (!t || (!measure_modifiers_.empty() &&
               std::find(measure_modifiers_.begin(), measure_modifiers_.end(), name) == measure_modifiers_.end()))
      throw std::invalid_argument("unknown measure modifier '" + name + "' (see modifiers/measurement_modifiers.json)");
    out.emplace_back(t, std::abs(v));
  }
  return out;
}

void HumanLibrary::build(const MacroParams& p, std::span<Vec3f> out) const {
  if (out.size() != base_.positions.size())
    throw std::invalid_argument("HumanLibrary::build: output has the wrong vertex count");
  std::copy(base_.positions.begin(), base_.positions.end(), out.begin());
  // Fixed target order and float accumulation in that order: deterministic.
  // Each coordinate gets out + wf * delta per target, by 16-float chunks
  // where the machine has AVX-512 (contiguous loads: the sparse loop's
  // scattered ones were 8% of a regenerated body, issue 26), else one by
  // one: the same operations, so the same bits.
  static const bool wide = __builtin_cpu_supports("avx512f");
  static_assert(sizeof(Vec3f) == 3 * sizeof(float), "interleaved coordinates");
  for (const auto& [t, w] : active_targets(p)) {
    const float wf = static_cast<float>(w);
    const std::size_t k = t >= macro_.data() && t < macro_.data() + macro_.size()
                              ? static_cast<std::size_t>(t - macro_.data())
                              : macro_.size() + static_cast<std::size_t>(t - measure_.data());
    if (wide && k < chunks_.size() && !chunks_[k].chunk.empty()) {
      add_chunks_avx512(reinterpret_cast<float*>(out.data()), chunks_[k].chunk.data(), chunks_[k].mask.data(),
                        chunks_[k].value.data(), chunks_[k].chunk.size(), wf);
      continue;
    }
    for (std::size_t q = 0; q < t->index.size(); ++q) out[t->index[q]] += wf * t->delta[q];
  }
  // Onto the floor: the lowest skin vertex at y = 0 exactly (x - x = 0).
  float floor_y = std::numeric_limits<float>::infinity();
  for (std::uint32_t v = 0; v < skin_vertices_; ++v) floor_y = std::min(floor_y, out[v].y());
  if (skin_vertices_ > 0)
    for (Vec3f& q : out) q.y() -= floor_y;
}


// --------------------------------------------------------- reference body

namespace {

// Mirror partner of every skin vertex across x = 0 (nearest vertex to the
// reflected position, through a uniform hash grid).
std::vector<std::uint32_t> mirror_map(std::span<const Vec3d> p) {
  const double cell = 0.01;  // metres
  std::map<std::array<long, 3>, std::vector<std::uint32_t>> grid;
  auto key = [&](const Vec3d& q) {
    return std::array<long, 3>{static_cast<long>(std::floor(q.x() / cell)), static_cast<long>(std::floor(q.y() / cell)),
                               static_cast<long>(std::floor(q.z() / cell))};
  };
  for (std::uint32_t i = 0; i < p.size(); ++i) grid[key(p[i])].push_back(i);
  std::vector<std::uint32_t> out(p.size());
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    const Vec3d q(-p[i].x(), p[i].y(), p[i].z());
    const auto k = key(q);
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t bi = i;
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (auto j : it->second) {
            const double d = (p[j] - q).squaredNorm();
            if (d < best || (d == best && j < bi)) best = d, bi = j;
          }
        }
    out[i] = bi;
  }
  return out;
}

SurfaceLocation vertex_location(std::uint32_t v) {
  SurfaceLocation l;
  l.kind = AttribNodeKind::kVertex;
  l.element = v;
  return l;
}

// Point at parameter t on the loop segment a->b: on the mesh edge if there is
// one, else at the nearer vertex.
SurfaceLocation segment_location(const Model& m, std::uint32_t a, std::uint32_t b, double t) {
  const HalfedgeIdx h = m.find_halfedge(NodeIdx{a}, NodeIdx{b});
  if (!h.valid()) return vertex_location(t < 0.5 ? a : b);
  SurfaceLocation l;
  l.kind = AttribNodeKind::kEdge;
  l.element = h.value;
  l.param = Vec3d(t, 0, 0);
  return l;
}

// Crossing of a closed vertex loop with the plane n.x = d, restricted to
// points where `accept` holds; the first such crossing in loop order.
bool loop_crossing(const Model& m, std::span<const std::uint32_t> loop, std::span<const Vec3d> p, const Vec3d& n,
                   double d, const std::function<bool(const Vec3d&)>& accept, SurfaceLocation& out) {
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const std::uint32_t a = loop[k], b = loop[(k + 1) % loop.size()];
    const double da = n.dot(p[a]) - d, db = n.dot(p[b]) - d;
    if ((da < 0) == (db < 0)) continue;
    const double t = da / (da - db);
    if (!accept((1 - t) * p[a] + t * p[b])) continue;
    out = segment_location(m, a, b, t);
    return true;
  }
  return false;
}

Vec3d centroid(std::span<const std::uint32_t> loop, std::span<const Vec3d> p) {
  Vec3d c = Vec3d::Zero();
  for (auto v : loop) c += p[v];
  return c / static_cast<double>(loop.size());
}

std::vector<SurfaceLocation> to_locations(std::span<const SectionPoint> pts) {
  std::vector<SurfaceLocation> l;
  for (const auto& q : pts) l.push_back(q.where);
  return l;
}

void check(const Status& s) {
  if (!s) throw Error(s);
}

}  // namespace

ReferenceBody make_reference_body(const HumanLibrary& lib) {
  std::vector<Vec3f> pos(lib.vertex_count());
  lib.build(MacroParams{}, pos);
  return make_reference_body(lib, pos);
}

ReferenceBody make_reference_body(const HumanLibrary& lib, std::span<const Vec3f> full) {
  const std::uint32_t ns = lib.skin_vertex_count();
  const auto* body = lib.base().group("body");
  std::vector<Vec3d> p(ns);
  for (std::uint32_t v = 0; v < ns; ++v) p[v] = kMakeHumanToMetres * full[v].cast<double>();
  ReferenceBody rb;
  auto s = add_polygon_surface(rb.model, "skin", {p, body->face_offsets, body->face_nodes});
  if (!s) throw Error(s.status());
  rb.skin = s->idx;
  const Model& m = rb.model;

  auto loop_of = [&](const std::string& name) {
    auto it = lib.measures().find(name);
    if (it == lib.measures().end()) throw Error(Status(ErrorCode::kParse, "measures.json has no loop '" + name + "'"));
    std::vector<std::uint32_t> l;
    for (auto v : it->second)
      if (l.empty() || l.back() != v) l.push_back(v);
    if (l.size() > 1 && l.front() == l.back()) l.pop_back();
    return l;
  };
  std::int32_t next_id = 1;
  std::map<std::string, std::vector<std::uint32_t>> loops;
  auto add_loop = [&](const std::string& name, const std::vector<std::uint32_t>& l) {
    std::vector<SurfaceLocation> path;
    for (auto v : l) path.push_back(vertex_location(v));
    check(add_feature_curve(rb, next_id++, name, path, true));
    loops[name] = l;
  };
  const char* torso[][2] = {{"neck-circ", "neck"},           {"bust-circ", "bust"}, {"underbust-circ", "underbust"},
                            {"waist-circ", "waist"},         {"hips-circ", "hip"}};
  for (auto& t : torso) add_loop(t[1], loop_of(t[0]));
  const auto mirror = mirror_map(p);
  const char* limbs[][2] = {{"thigh-circ", "thigh"},       {"knee-circ", "knee"},   {"calf-circ", "calf"},
                            {"ankle-circ", "ankle"},       {"upperarm-circ", "upperarm"}, {"wrist-circ", "wrist"}};
  for (auto& t : limbs) {
    auto l = loop_of(t[0]);
    const bool left = centroid(l, p).x() > 0;  // +x is the body's left (y up, z front)
    std::vector<std::uint32_t> r;
    for (auto it = l.rbegin(); it != l.rend(); ++it) r.push_back(mirror[*it]);  // reversed keeps orientation
    add_loop(std::string(left ? "left_" : "right_") + t[1], l);
    add_loop(std::string(left ? "right_" : "left_") + t[1], r);
  }

  // Centre lines: the sagittal section, split at its top and its crotch.
  const Vec3d neck_c = centroid(loops["neck"], p), waist_c = centroid(loops["waist"], p);
  auto sag = plane_section(m, rb.skin, Vec3d(1, 0, 0), 0.0, p);
  const SectionChain* loop = nullptr;
  for (const auto& c : sag)
    if (c.closed && (!loop || c.points.size() > loop->points.size())) loop = &c;
  if (!loop) throw Error(Status(ErrorCode::kTopology, "the skin has no closed sagittal section"));
  {
    const auto& pts = loop->points;
    const double y_crotch_limit = centroid(loops["hip"], p).y();
    // Front and back arcs below the neck and above the crotch: walk from the
    // front-most / back-most point at waist height up and down.
    auto arc = [&](bool front) {
      std::size_t best = 0;
      double bd = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const double dz = front ? pts[i].p.z() - waist_c.z() : waist_c.z() - pts[i].p.z();
        if (dz <= 0) continue;
        const double dy = std::abs(pts[i].p.y() - waist_c.y());
        if (dy < bd) bd = dy, best = i;
      }
      const std::size_t n = pts.size();
      auto in_range = [&](std::size_t i) {
        const double y = pts[i].p.y();
        const double dz = front ? pts[i].p.z() - neck_c.z() : neck_c.z() - pts[i].p.z();
        return y <= neck_c.y() && y >= y_crotch_limit - 0.12 && dz > -0.05;
      };
      // Direction along which y increases from `best`.
      const int up = pts[(best + 1) % n].p.y() > pts[best].p.y() ? 1 : -1;
      std::size_t top = best, bot = best;
      for (std::size_t k = 1; k < n; ++k) {
        const std::size_t i = (best + n + up * static_cast<long>(k)) % n;
        if (!in_range(i)) break;
        top = i;
      }
      for (std::size_t k = 1; k < n; ++k) {
        const std::size_t i = (best + n - up * static_cast<long>(k)) % n;
        if (!in_range(i)) break;
        bot = i;
      }
      std::vector<SectionPoint> out;
      for (std::size_t i = top;; i = (i + n - up) % n) {  // top to bottom
        out.push_back(pts[i]);
        if (i == bot) break;
      }
      return out;
    };
    auto front = arc(true), back = arc(false);
    check(add_feature_curve(rb, next_id++, "centre_front", to_locations(front), false));
    check(add_feature_curve(rb, next_id++, "centre_back", to_locations(back), false));
  }

  // Side lines: the coronal section through the waist centroid.
  const double y_top = centroid(loops["bust"], p).y() + 0.5 * (centroid(loops["bust"], p).y() -
                                                               centroid(loops["underbust"], p).y());
  const double y_bot = centroid(loops["hip"], p).y();
  auto cor = plane_section(m, rb.skin, Vec3d(0, 0, 1), waist_c.z(), p);
  for (int sgn : {+1, -1}) {
    // Seed: the waist loop's outermost point on this side.
    Vec3d seed = waist_c;
    for (auto v : loops["waist"])
      if (sgn * p[v].x() > sgn * seed.x()) seed = p[v];
    const SectionChain* best_c = nullptr;
    std::size_t best_i = 0;
    double bd = std::numeric_limits<double>::infinity();
    for (const auto& c : cor)
      for (std::size_t i = 0; i < c.points.size(); ++i) {
        const double dd = (c.points[i].p - seed).squaredNorm();
        if (dd < bd) bd = dd, best_c = &c, best_i = i;
      }
    if (!best_c) throw Error(Status(ErrorCode::kTopology, "no coronal section through the waist"));
    const auto& pts = best_c->points;
    const std::size_t n = pts.size();
    auto step = [&](std::size_t i, int dir) -> std::optional<std::size_t> {
      if (!best_c->closed && ((dir < 0 && i == 0) || (dir > 0 && i + 1 == n))) return std::nullopt;
      return (i + n + dir) % n;
    };
    const int up = pts[*step(best_i, 1)].p.y() > pts[best_i].p.y() ? 1 : -1;
    std::size_t top = best_i, bot = best_i;
    for (auto i = step(best_i, up); i && pts[*i].p.y() <= y_top && sgn * pts[*i].p.x() > 0; i = step(*i, up)) top = *i;
    for (auto i = step(best_i, -up); i && pts[*i].p.y() >= y_bot && sgn * pts[*i].p.x() > 0; i = step(*i, -up))
      bot = *i;
    std::vector<SectionPoint> line;
    for (std::size_t i = top;; i = (i + n - up) % n) {
      line.push_back(pts[i]);
      if (i == bot) break;
    }
    check(add_feature_curve(rb, next_id++, sgn > 0 ? "left_side" : "right_side", to_locations(line), false));
  }

  // Feature points: torso girths x centre and side lines.
  std::int32_t pid = 1;
  for (const char* g : {"neck", "bust", "underbust", "waist", "hip"}) {
    const auto& l = loops[g];
    const Vec3d c = centroid(l, p);
    const std::int32_t gid = rb.find_curve(g)->id;
    struct Line {
      const char* name;
      Vec3d n;
      double d;
      std::function<bool(const Vec3d&)> accept;
    };
    const std::vector<Line> lines = {
        {"centre_front", Vec3d(1, 0, 0), 0.0, [&](const Vec3d& q) { return q.z() > c.z(); }},
        {"centre_back", Vec3d(1, 0, 0), 0.0, [&](const Vec3d& q) { return q.z() < c.z(); }},
        {"left_side", Vec3d(0, 0, 1), waist_c.z(), [&](const Vec3d& q) { return q.x() > 0; }},
        {"right_side", Vec3d(0, 0, 1), waist_c.z(), [&](const Vec3d& q) { return q.x() < 0; }},
    };
    for (const auto& line : lines) {
      const bool side = line.name[0] == 'l' || line.name[0] == 'r';
      if (side && (c.y() > y_top || c.y() < y_bot - 1e-9)) continue;  // the side lines do not reach this girth
      SurfaceLocation where;
      if (!loop_crossing(m, l, p, line.n, line.d, line.accept, where)) continue;
      check(add_feature_point(rb, pid++, std::string(g) + "_x_" + line.name, where, gid,
                              rb.find_curve(line.name)->id));
    }
  }
  return rb;
}

// ------------------------------------------------------------------- source

MakeHumanSource::MakeHumanSource(std::shared_ptr<const HumanLibrary> lib, std::vector<MacroParams> params,
                                 std::shared_ptr<const ReferenceBody> reference)
    : lib_(std::move(lib)), params_(std::move(params)), reference_(std::move(reference)) {}

MakeHumanSource::MakeHumanSource(std::shared_ptr<const HumanLibrary> lib, std::size_t count, std::uint64_t seed,
                                 std::shared_ptr<const ReferenceBody> reference)
    : lib_(std::move(lib)), sampled_(true), count_(count), seed_(seed), reference_(std::move(reference)) {}

std::string MakeHumanSource::body_name(std::size_t i) const {
  std::ostringstream s;
  s << "makehuman-" << std::setw(5) << std::setfill('0') << i;
  return s.str();
}

std::vector<std::pair<std::string, std::string>> MakeHumanSource::parameters(std::size_t i) const {
  const MacroParams p = params(i);
  std::vector<std::pair<std::string, std::string>> out;
  out.emplace_back("sampled_sex", p.gender < 0.5 ? "female" : "male");
  {
    char b[32];
    std::snprintf(b, sizeof b, "%.4f", lib_->stature(p));  // 0.1 mm
    out.emplace_back("sampled_stature_m", b);
  }
  for (const auto& [name, v] : {std::pair{"gender", p.gender}, std::pair{"age", p.age}, std::pair{"muscle", p.muscle},
                                std::pair{"weight", p.weight}, std::pair{"height", p.height},
                                std::pair{"proportions", p.proportions}}) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4f", v);
    out.emplace_back(std::string("sampled_") + name + "_slider", b);
  }
  return out;
}

std::vector<Vec3d> MakeHumanSource::skin_positions(std::size_t i) const {
  std::vector<Vec3f> full(lib_->vertex_count());
  lib_->build(params(i), full);
  std::vector<Vec3d> p(reference_->model.nodes.slots.capacity(), Vec3d::Zero());
  for (std::size_t v = 0; v < p.size(); ++v) p[v] = kMakeHumanToMetres * full[v].cast<double>();
  return p;
}

void MakeHumanSource::generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                               const ExecContext& ctx) const {
  out.clear();
  const std::size_t end = std::min(size(), first + count);
  if (first >= end) return;
  std::vector<std::vector<Vec3d>> bodies(end - first);
  std::vector<std::string> errors(end - first);
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, end - first, [&](std::size_t k) {
    try {
      bodies[k] = skin_positions(first + k);
    } catch (const std::exception& e) {
      errors[k] = e.what();
    }
  });
  out.reserve(end - first);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const std::size_t i = first + k;
    Status s = errors[k].empty() ? out.add(body_name(i), std::span<const Vec3d>(bodies[k]))
                                 : Status(ErrorCode::kInvalidArgument, errors[k]);
    if (!s) failures.push_back({i, body_name(i), s});
  }
}

}  // namespace atelier::makehuman
