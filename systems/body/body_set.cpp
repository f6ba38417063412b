#include <atelier/systems/body/body_set.h>

#include <algorithm>
#include <limits>
#include <sstream>

#include <atelier/engine/parallel.h>
#include <atelier/io/obj.h>

namespace atelier {

BodySet::BodySet(std::shared_ptr<const ReferenceBody> reference)
    : reference_(std::move(reference)), n_(reference_ ? reference_->model.nodes.slots.capacity() : 0) {}

namespace {
template <class V>
Status add_impl(std::vector<float>& data, std::vector<std::string>& names, std::size_t n, std::string name,
                std::span<const V> p) {
  if (p.size() != n) {
    std::ostringstream s;
    s << "body '" << name << "' has " << p.size() << " positions, the body set needs " << n;
    return {ErrorCode::kMismatch, s.str()};
  }
  // Stored as float: a finite double beyond the float range (1e300) would
  // become infinity.
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  for (std::size_t v = 0; v < n; ++v)
    if (!p[v].allFinite() || p[v].template cast<double>().cwiseAbs().maxCoeff() > kFloatMax) {
      std::ostringstream s;
      s << "body '" << name << "': node " << v << " has a non-finite position"
        << (p[v].allFinite() ? " once stored as float (a coordinate beyond 3.4e38)" : "");
      return {ErrorCode::kDegenerate, s.str()};
    }
  const std::size_t base = data.size();
  data.resize(base + 3 * n);
  for (std::size_t v = 0; v < n; ++v) {
    data[base + v] = static_cast<float>(p[v].x());
    data[base + n + v] = static_cast<float>(p[v].y());
    data[base + 2 * n + v] = static_cast<float>(p[v].z());
  }
  names.push_back(std::move(name));
  return {};
}
}  // namespace

Status BodySet::add(std::string name, std::span<const Vec3d> p) { return add_impl(data_, names_, n_, std::move(name), p); }
Status BodySet::add(std::string name, std::span<const Vec3f> p) { return add_impl(data_, names_, n_, std::move(name), p); }

void BodySet::clear() noexcept {
  data_.clear();
  names_.clear();
}

void BodySet::positions(std::size_t b, std::span<Vec3d> out) const noexcept {
  const float* base = data_.data() + b * 3 * n_;
  for (std::size_t v = 0; v < n_ && v < out.size(); ++v) out[v] = Vec3d(base[v], base[n_ + v], base[2 * n_ + v]);
}

std::vector<Vec3d> BodySet::positions(std::size_t b) const {
  std::vector<Vec3d> p(n_);
  positions(b, p);
  return p;
}

// ------------------------------------------------------------ OBJ directory

Expected<std::vector<Vec3d>> read_body_obj(const std::filesystem::path& file, const ReferenceBody& ref, double scale) {
  return read_body_obj(file, ref, BodyFrame{scale, UpAxis::kY});
}

Expected<std::vector<Vec3d>> read_body_obj(const std::filesystem::path& file, const ReferenceBody& ref,
                                           const BodyFrame& frame) {
  Model m;
  try {
    m = read_obj(file);
  } catch (const Error& e) {
    return e.status();
  }
  const Model& r = ref.model;
  auto mismatch = [&](const std::string& what) {
    return Status(ErrorCode::kMismatch, file.string() + ": topology differs from the reference body: " + what);
  };
  // Compare the skin: live node count and face corners in order.
  if (m.num_nodes() != r.num_nodes()) {
    std::ostringstream s;
    s << m.num_nodes() << " vertices, the reference has " << r.num_nodes();
    return mismatch(s.str());
  }
  if (m.num_faces() != r.faces.slots.size()) {
    std::ostringstream s;
    s << m.num_faces() << " faces, the reference has " << r.num_faces();
    return mismatch(s.str());
  }
  // Reference nodes in index order map to file vertices in file order.
  std::vector<NodeIdx> ref_nodes;
  for (std::uint32_t v = 0; v < r.nodes.slots.capacity(); ++v)
    if (r.alive(NodeIdx{v})) ref_nodes.push_back(NodeIdx{v});
  std::vector<std::uint32_t> file_to_ref(m.nodes.slots.capacity(), ~0u);
  {
    std::uint32_t k = 0;
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
      if (m.alive(NodeIdx{v})) file_to_ref[v] = ref_nodes[k++].value;
  }
  std::vector<NodeIdx> fa, fb;
  std::uint32_t fr = 0;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    while (!r.alive(FaceIdx{fr})) ++fr;
    m.face_nodes(FaceIdx{f}, fa);
    r.face_nodes(FaceIdx{fr}, fb);
    bool same = fa.size() == fb.size();
    for (std::size_t k = 0; same && k < fa.size(); ++k) same = file_to_ref[fa[k].value] == fb[k].value;
    if (!same) {
      std::ostringstream s;
      s << "face " << f << " has other vertices than the reference's face " << fr;
      return mismatch(s.str());
    }
    ++fr;
  }
  std::vector<Vec3d> pos(r.nodes.slots.capacity(), Vec3d::Zero());
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) pos[file_to_ref[v]] = frame.to_engine(m.position(NodeIdx{v}));
  return pos;
}

ObjDirectorySource::ObjDirectorySource(std::filesystem::path dir, std::shared_ptr<const ReferenceBody> reference,
                                       double scale)
    : ObjDirectorySource(std::move(dir), std::move(reference), BodyFrame{scale, UpAxis::kY}) {}

ObjDirectorySource::ObjDirectorySource(std::filesystem::path dir, std::shared_ptr<const ReferenceBody> reference,
                                       BodyFrame frame)
    : dir_(std::move(dir)), reference_(std::move(reference)), frame_(frame) {
  namespace fs = std::filesystem;
  if (Status s = frame_.check(); !s) throw Error(Status(s.code(), dir_.string() + ": " + s.message()));
  if (!fs::is_directory(dir_)) throw Error(Status(ErrorCode::kIo, dir_.string() + ": not a directory"));
  for (const auto& e : fs::directory_iterator(dir_)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (e.is_regular_file() && ext == ".obj") files_.push_back(e.path());
  }
  std::sort(files_.begin(), files_.end());
}

void ObjDirectorySource::generate(std::size_t first, std::size_t count, BodySet& out,
                                  std::vector<BodyFailure>& failures, const ExecContext& ctx) const {
  out.clear();
  const std::size_t end = std::min(files_.size(), first + count);
  if (first >= end) return;
  std::vector<Expected<std::vector<Vec3d>>> loaded(end - first, Status(ErrorCode::kInternal, "not loaded"));
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, end - first, [&](std::size_t k) { loaded[k] = read_body_obj(files_[first + k], *reference_, frame_); });
  for (std::size_t k = 0; k < loaded.size(); ++k) {
    const std::size_t i = first + k;
    Status s = loaded[k] ? out.add(body_name(i), std::span<const Vec3d>(*loaded[k])) : loaded[k].status();
    if (!s) failures.push_back({i, body_name(i), s});
  }
}

}  // namespace atelier
