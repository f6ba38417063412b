// The shared machinery of bind.h: argument checks, output arrays, errors.
#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "bind.h"

namespace atelier::python {

namespace {

std::string shape_text(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s << (d ? ", " : "") << a.shape(d);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

std::string dtype_text(const py::array& a) {
  return py::str(py::object(a.dtype())).cast<std::string>();
}

/// The argument as an ndarray (np.asarray for lists and other sequences).
py::array as_array(py::handle obj, const char* what) {
  if (py::isinstance<py::array>(obj)) return py::reinterpret_borrow<py::array>(obj);
  try {
    return py::module_::import("numpy").attr("asarray")(obj);
  } catch (py::error_already_set& e) {
    if (e.matches(PyExc_KeyboardInterrupt)) throw;
    value_error(std::string(what) + ": not an array (" + e.what() + ")");
  }
}

bool is_float_dtype(const py::array& a) {
  return a.dtype().kind() == 'f' && (a.itemsize() == 4 || a.itemsize() == 8);
}

std::string point_text(double x, double y, double z) {
  std::ostringstream s;
  s << "(" << x << ", " << y << ", " << z << ")";
  return s.str();
}

/// Element (i, j) of a 2-D integer array of any width and signedness.
std::int64_t int_at(const char* base, const py::array& a, py::ssize_t i, py::ssize_t j) {
  const char* p = base + i * a.strides(0) + j * a.strides(1);
  const bool is_signed = a.dtype().kind() == 'i';
  switch (a.itemsize()) {
    case 1:
      return is_signed ? std::int64_t{*reinterpret_cast<const std::int8_t*>(p)}
                       : *reinterpret_cast<const std::uint8_t*>(p);
    case 2:
      return is_signed ? std::int64_t{*reinterpret_cast<const std::int16_t*>(p)}
                       : *reinterpret_cast<const std::uint16_t*>(p);
    case 4:
      return is_signed ? std::int64_t{*reinterpret_cast<const std::int32_t*>(p)}
                       : *reinterpret_cast<const std::uint32_t*>(p);
    default: {
      if (is_signed) return *reinterpret_cast<const std::int64_t*>(p);
      const std::uint64_t u = *reinterpret_cast<const std::uint64_t*>(p);
      return u > static_cast<std::uint64_t>(INT64_MAX) ? -1 : static_cast<std::int64_t>(u);
    }
  }
}

void add_face_checked(PolygonSoup& out, const std::vector<std::int64_t>& face, std::size_t f, std::size_t vertex_count,
                      const char* what) {
  if (face.size() < 3)
    value_error(std::string(what) + ": face " + std::to_string(f) + " has " + std::to_string(face.size()) +
                " corners (at least 3)");
  for (const std::int64_t v : face)
    if (v < 0 || static_cast<std::uint64_t>(v) >= vertex_count)
      value_error(std::string(what) + ": face " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                  ", the mesh has " + std::to_string(vertex_count) + " vertices (indices run from 0)");
  for (const std::int64_t v : face) out.face_nodes.push_back(static_cast<std::uint32_t>(v));
  out.face_offsets.push_back(static_cast<std::uint32_t>(out.face_nodes.size()));
}

}  // namespace

// ------------------------------------------------------------ errors

void raise(const Status& s) {
  throw Error(s);
}

void value_error(const std::string& message) {
  throw py::value_error(message);
}

void register_errors(py::module_& m) {
  (void)m;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyObject* type = PyExc_RuntimeError;
      switch (e.status().code()) {
        case ErrorCode::kIo:
          type = PyExc_OSError;
          break;
        case ErrorCode::kInvalidArgument:
        case ErrorCode::kTopology:
        case ErrorCode::kNonManifold:
        case ErrorCode::kJointRefused:
        case ErrorCode::kDegenerate:
        case ErrorCode::kParse:
        case ErrorCode::kMismatch:
        case ErrorCode::kUnsupported:
          type = PyExc_ValueError;
          break;
        default:
          break;
      }
      PyErr_SetString(type, e.what());
    }
  });
}

// ------------------------------------------------------------ shared classes

std::shared_ptr<Mesh> mesh_of(Model model) {
  auto mesh = std::make_shared<Mesh>();
  mesh->soup = polygon_soup(model);
  mesh->soup.positions = {};  // the model's column is the positions
  mesh->model = std::make_shared<const Model>(std::move(model));
  return mesh;
}

std::shared_ptr<const Mesh> mesh_from(py::handle obj, const char* what) {
  if (py::isinstance<Mesh>(obj)) return obj.cast<std::shared_ptr<Mesh>>();
  if (py::isinstance<Body>(obj)) {
    const auto body = obj.cast<std::shared_ptr<Body>>();
    auto mesh = std::make_shared<Mesh>();
    mesh->model = std::shared_ptr<const Model>(body->reference, &body->reference->model);
    mesh->soup = body->skin;
    return mesh;
  }
  if ((py::isinstance<py::tuple>(obj) || py::isinstance<py::list>(obj)) && py::len(obj) == 2) {
    auto mesh = std::make_shared<Mesh>();
    mesh->soup = soup_from(obj[py::int_(0)], obj[py::int_(1)], what);
    return mesh;
  }
  throw py::type_error(std::string(what) + ": expected a Mesh, a Body or a (vertices, faces) pair, got " +
                       py::str(py::type::of(obj).attr("__name__")).cast<std::string>());
}

Model model_from(py::handle obj, const char* what) {
  const std::shared_ptr<const Mesh> in = mesh_from(obj, what);
  Model model;
  if (in->model)
    model = *in->model;
  else
    (void)unwrap(add_polygon_surface(model, what, in->soup));
  return model;
}

std::shared_ptr<Body> Body::of(std::shared_ptr<const ReferenceBody> reference) {
  auto b = std::make_shared<Body>();
  b->skin = polygon_soup(reference->model, reference->skin);
  b->skin.positions = {};
  b->reference = std::move(reference);
  return b;
}

std::vector<Vec3d> Body::positions_arg(py::handle array, const char* what) const {
  std::vector<Vec3d> p = points_from(array, what);
  if (p.size() != node_count())
    value_error(std::string(what) + ": " + std::to_string(p.size()) + " vertices; the body has " +
                std::to_string(node_count()));
  return p;
}

// ------------------------------------------------------------ arrays in

std::vector<Vec3d> points_from(py::handle obj, const char* what) {
  const py::array a = as_array(obj, what);
  if (!is_float_dtype(a)) value_error(std::string(what) + ": dtype " + dtype_text(a) + "; expected float32 or float64");
  if (a.ndim() != 2 || a.shape(1) != 3)
    value_error(std::string(what) + ": expected an (n, 3) array, got shape " + shape_text(a));
  const auto n = static_cast<std::size_t>(a.shape(0));
  std::vector<Vec3d> out(n);
  const char* base = static_cast<const char*>(a.data());
  const bool f32 = a.itemsize() == 4;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const char* p = base + static_cast<py::ssize_t>(i) * a.strides(0) + k * a.strides(1);
      out[i][k] = f32 ? static_cast<double>(*reinterpret_cast<const float*>(p)) : *reinterpret_cast<const double*>(p);
    }
    if (!out[i].allFinite())
      value_error(std::string(what) + ": vertex " + std::to_string(i) + " is not finite " +
                  point_text(out[i].x(), out[i].y(), out[i].z()));
  }
  return out;
}

void faces_into(py::handle obj, std::size_t vertex_count, PolygonSoup& out, const char* what) {
  out.face_offsets.assign(1, 0);
  out.face_nodes.clear();
  const std::string help = "; expected an (F, k) integer array (k >= 3) or a list of polygons";
  std::optional<py::array> a;
  if (py::isinstance<py::array>(obj)) {
    a = py::reinterpret_borrow<py::array>(obj);
  } else {
    try {
      py::array t = py::module_::import("numpy").attr("asarray")(obj);
      if (t.ndim() == 2 && t.dtype().kind() != 'O') a = t;
    } catch (py::error_already_set& e) {
      if (e.matches(PyExc_KeyboardInterrupt)) throw;
    }
  }
  if (a) {
    const char kind = a->dtype().kind();
    if (kind != 'i' && kind != 'u') value_error(std::string(what) + ": dtype " + dtype_text(*a) + help);
    if (a->ndim() != 2 || (a->shape(0) > 0 && a->shape(1) < 3))
      value_error(std::string(what) + ": shape " + shape_text(*a) + help);
    const char* base = static_cast<const char*>(a->data());
    std::vector<std::int64_t> face(static_cast<std::size_t>(a->shape(1)));
    out.face_offsets.reserve(static_cast<std::size_t>(a->shape(0)) + 1);
    out.face_nodes.reserve(static_cast<std::size_t>(a->shape(0) * a->shape(1)));
    for (py::ssize_t f = 0; f < a->shape(0); ++f) {
      for (py::ssize_t j = 0; j < a->shape(1); ++j) face[static_cast<std::size_t>(j)] = int_at(base, *a, f, j);
      add_face_checked(out, face, static_cast<std::size_t>(f), vertex_count, what);
    }
    return;
  }
  // A ragged sequence of polygons.
  if (!py::isinstance<py::sequence>(obj) || py::isinstance<py::str>(obj))
    value_error(std::string(what) + ": " + py::str(py::type::of(obj).attr("__name__")).cast<std::string>() + help);
  std::vector<std::int64_t> face;
  std::size_t f = 0;
  for (py::handle item : obj) {
    py::array p = as_array(item, what);
    const char kind = p.dtype().kind();
    if (p.ndim() != 1 || (kind != 'i' && kind != 'u'))
      value_error(std::string(what) + ": face " + std::to_string(f) + " is not a 1-D list of integers" + help);
    face.resize(static_cast<std::size_t>(p.shape(0)));
    py::array p2 = p.reshape({p.shape(0), py::ssize_t{1}});
    for (py::ssize_t j = 0; j < p.shape(0); ++j)
      face[static_cast<std::size_t>(j)] = int_at(static_cast<const char*>(p2.data()), p2, j, 0);
    add_face_checked(out, face, f++, vertex_count, what);
  }
}

PolygonSoup soup_from(py::handle vertices, py::handle faces, const char* what) {
  PolygonSoup s;
  s.positions = points_from(vertices, (std::string(what) + " vertices").c_str());
  faces_into(faces, s.positions.size(), s, (std::string(what) + " faces").c_str());
  return s;
}

BodyBatch::BodyBatch(py::handle obj, std::size_t node_count, const char* what) : what_(what) {
  array_ = as_array(obj, what);
  if (!is_float_dtype(array_))
    value_error(std::string(what) + ": dtype " + dtype_text(array_) + "; expected float32 or float64");
  if (array_.ndim() != 3 || array_.shape(2) != 3)
    value_error(std::string(what) + ": expected a (B, n, 3) array of B bodies, got shape " + shape_text(array_));
  if (node_count != 0 && static_cast<std::size_t>(array_.shape(1)) != node_count)
    value_error(std::string(what) + ": " + std::to_string(array_.shape(1)) +
                " vertices per body; the body family has " + std::to_string(node_count));
  bodies_ = static_cast<std::size_t>(array_.shape(0));
  nodes_ = static_cast<std::size_t>(array_.shape(1));
  is_float_ = array_.itemsize() == 4;
  for (int d = 0; d < 3; ++d) stride_[d] = array_.strides(d);
  data_ = static_cast<const char*>(array_.data());
}

Status BodyBatch::check(const ExecContext& ctx) const {
  // The first non-finite vertex of each body, in parallel; the lowest body reported.
  std::vector<std::int64_t> bad(bodies_, -1);
  ExecContext per_body = ctx;
  per_body.sequential_threshold = 2;
  per_body.grain = 1;
  par::for_each_n(per_body, bodies_, [&](std::size_t b) {
    const char* body = data_ + static_cast<py::ssize_t>(b) * stride_[0];
    for (std::size_t v = 0; v < nodes_ && bad[b] < 0; ++v) {
      const char* row = body + static_cast<py::ssize_t>(v) * stride_[1];
      for (int k = 0; k < 3; ++k) {
        const char* p = row + k * stride_[2];
        const double x = is_float_ ? double{*reinterpret_cast<const float*>(p)} : *reinterpret_cast<const double*>(p);
        if (!std::isfinite(x)) bad[b] = static_cast<std::int64_t>(v);
      }
    }
  });
  for (std::size_t b = 0; b < bodies_; ++b)
    if (bad[b] >= 0)
      return {ErrorCode::kInvalidArgument, std::string(what_) + ": body " + std::to_string(b) + ", vertex " +
                                               std::to_string(bad[b]) + " is not finite"};
  return {};
}

namespace {
template <class V>
void gather(const char* data, const py::ssize_t* stride, bool is_float, std::size_t b, std::size_t n,
            std::vector<V>& out) {
  out.resize(n);
  const char* body = data + static_cast<py::ssize_t>(b) * stride[0];
  for (std::size_t v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k) {
      const char* p = body + static_cast<py::ssize_t>(v) * stride[1] + k * stride[2];
      const double x = is_float ? double{*reinterpret_cast<const float*>(p)} : *reinterpret_cast<const double*>(p);
      out[v][k] = static_cast<typename V::Scalar>(x);
    }
}
}  // namespace

void BodyBatch::get(std::size_t b, std::vector<Vec3f>& out) const {
  gather(data_, stride_, is_float_, b, nodes_, out);
}
void BodyBatch::get(std::size_t b, std::vector<Vec3d>& out) const {
  gather(data_, stride_, is_float_, b, nodes_, out);
}

std::span<const Vec3f> BodyBatch::floats(std::size_t b) const noexcept {
  if (!is_float_ || stride_[2] != 4 || stride_[1] != 12 || (reinterpret_cast<std::uintptr_t>(data_) % 4) != 0 ||
      stride_[0] % 4 != 0)
    return {};
  return {reinterpret_cast<const Vec3f*>(data_ + static_cast<py::ssize_t>(b) * stride_[0]), nodes_};
}

std::span<const Vec3d> BodyBatch::doubles(std::size_t b) const noexcept {
  if (is_float_ || stride_[2] != 8 || stride_[1] != 24 || (reinterpret_cast<std::uintptr_t>(data_) % 8) != 0 ||
      stride_[0] % 8 != 0)
    return {};
  return {reinterpret_cast<const Vec3d*>(data_ + static_cast<py::ssize_t>(b) * stride_[0]), nodes_};
}

int threads_arg(int threads) {
  if (threads < 0) value_error("threads must be 0 (all cores) or more, got " + std::to_string(threads));
  return threads;
}

bool float32_arg(py::handle dtype) {
  const py::dtype d = py::dtype::from_args(py::reinterpret_borrow<py::object>(dtype));
  if (d.kind() == 'f' && d.itemsize() == 4) return true;
  if (d.kind() == 'f' && d.itemsize() == 8) return false;
  value_error("dtype must be float32 or float64, got " + py::str(py::handle(d)).cast<std::string>());
}

// ------------------------------------------------------------ arrays out

py::object faces_out(std::span<const std::uint32_t> offsets, std::span<const std::uint32_t> nodes, py::handle owner) {
  const std::size_t nf = offsets.empty() ? 0 : offsets.size() - 1;
  if (nf == 0) return py::array_t<std::uint32_t>(std::vector<py::ssize_t>{0, 3});
  const std::uint32_t k = offsets[1] - offsets[0];
  bool uniform = true;
  for (std::size_t f = 1; f < nf && uniform; ++f) uniform = offsets[f + 1] - offsets[f] == k;
  if (uniform) return view(nodes.data(), {static_cast<py::ssize_t>(nf), static_cast<py::ssize_t>(k)}, owner);
  py::list faces;
  for (std::size_t f = 0; f < nf; ++f) {
    py::array_t<std::uint32_t> face(static_cast<py::ssize_t>(offsets[f + 1] - offsets[f]));
    std::memcpy(face.mutable_data(), nodes.data() + offsets[f], sizeof(std::uint32_t) * (offsets[f + 1] - offsets[f]));
    faces.append(face);
  }
  return faces;
}

std::vector<Triangle> fan_triangles(const PolygonSoup& soup) {
  std::vector<Triangle> t;
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const auto c = soup.face(f);
    for (std::size_t j = 1; j + 1 < c.size(); ++j) t.push_back({c[0], c[j], c[j + 1]});
  }
  return t;
}

}  // namespace atelier::python
