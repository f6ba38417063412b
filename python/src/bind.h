// What every binding source shares: numpy arrays in (checked: shape, dtype,
// finite values, index ranges; each failure a ValueError naming the
// argument and the element), numpy arrays out (views onto engine columns
// that keep their owner alive, or arrays that adopt a moved vector), the
// engine's errors as Python exceptions, and long calls (GIL released, the
// work on a worker thread, progress relayed to a Python callback and
// KeyboardInterrupt turned into the engine's cancellation).
//
// One source per family binds its calls (bind_<family>.cpp) through
// bind_<family>(module); module.cpp calls them. The Python classes shared by
// several families (Mesh, Body) are declared here.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/body/reference_body.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace atelier {
struct GarmentFamily;
struct GarmentTemplate;
struct ProfileTemplate;
}  // namespace atelier

namespace atelier::python {

namespace py = pybind11;

// ------------------------------------------------------------ argument types
// Python objects checked by the binding itself (not by pybind11), named for
// the signatures that help() shows: `vertices: numpy.ndarray` instead of
// `vertices: handle`. Each accepts any object; the names are set below.
inline int accept_any(PyObject*) {
  return 1;
}
#define ATELIER_PY_ARG(Name)                          \
  class Name : public py::object {                    \
   public:                                            \
    PYBIND11_OBJECT_DEFAULT(Name, object, accept_any) \
  };
ATELIER_PY_ARG(Array)          // numpy.ndarray (or a sequence np.asarray converts)
ATELIER_PY_ARG(OptArray)       // numpy.ndarray | None
ATELIER_PY_ARG(Faces)          // (F, k) array or a list of polygons
ATELIER_PY_ARG(OptFaces)       // the same or None
ATELIER_PY_ARG(Progress)       // callable(stage, done, total) or None
ATELIER_PY_ARG(DType)          // numpy.dtype or its name
ATELIER_PY_ARG(Params)         // body parameters
ATELIER_PY_ARG(MeshLike)       // Mesh, Body or (vertices, faces)
ATELIER_PY_ARG(OptMeshLike)    // the same or None
ATELIER_PY_ARG(MeshOrArray)    // a mesh, or vertices with faces given apart
ATELIER_PY_ARG(MeshList)       // one mesh or a list
ATELIER_PY_ARG(GarmentSource)  // vertices, a Mesh or an OBJ path
ATELIER_PY_ARG(Garments)       // GarmentTemplate or a list
ATELIER_PY_ARG(Templates)      // ProfileTemplate or a list
ATELIER_PY_ARG(Colours)        // list of (r, g, b) or None
ATELIER_PY_ARG(Colour)         // (r, g, b) or None
ATELIER_PY_ARG(CurveName)      // str or int
ATELIER_PY_ARG(NDArray)        // a returned array (or a list of arrays for mixed polygons)
ATELIER_PY_ARG(Curves)         // a list of (k, 3) arrays or a curve file path
ATELIER_PY_ARG(Strokes)        // a stroke file path or its JSON as a dict
#undef ATELIER_PY_ARG

// ------------------------------------------------------------ errors

/// Throws the engine's error (translated to OSError, ValueError or
/// RuntimeError by the module's translator, message unchanged).
[[noreturn]] void raise(const Status& s);
template <class T>
T unwrap(Expected<T>&& e) {
  if (!e) raise(e.status());
  return std::move(*e);
}
inline void check(const Status& s) {
  if (!s) raise(s);
}
/// A ValueError with this message.
[[noreturn]] void value_error(const std::string& message);
/// Registers the translator of atelier::Error (module.cpp).
void register_errors(py::module_& m);

// ------------------------------------------------------------ shared classes

/// A polygon mesh: read from a file or built by the engine (then `model`
/// holds it and the positions are its node column), or given as arrays
/// (`soup.positions`). Faces are always in `soup` (CSR). Immutable once made.
struct Mesh {
  std::shared_ptr<const Model> model;
  PolygonSoup soup;
  [[nodiscard]] std::span<const Vec3d> positions() const noexcept {
    return model ? std::span<const Vec3d>(model->nodes.position) : std::span<const Vec3d>(soup.positions);
  }
};
/// A Mesh of an engine Model (moved in): its node column and its faces.
[[nodiscard]] std::shared_ptr<Mesh> mesh_of(Model model);

/// A body with its features (mannequin, MakeHuman, or a user's own mesh):
/// what garments and templates are encoded on and body sets share.
struct Body {
  std::shared_ptr<const ReferenceBody> reference;
  PolygonSoup skin;  // the skin's faces over node indices (positions: the model's column)
  [[nodiscard]] static std::shared_ptr<Body> of(std::shared_ptr<const ReferenceBody> reference);
  [[nodiscard]] std::size_t node_count() const noexcept { return reference->model.nodes.slots.capacity(); }
  /// Positions of another body of this topology: (n, 3), checked.
  [[nodiscard]] std::vector<Vec3d> positions_arg(py::handle array, const char* what) const;
};

/// A body family of the garment pipeline and the Body it was made from.
struct Family {
  std::shared_ptr<const GarmentFamily> family;
  std::shared_ptr<Body> body;
};
/// An encoded garment (immutable) and its family.
struct Garment {
  std::shared_ptr<const GarmentTemplate> garment;
  std::shared_ptr<Family> family;
  double reference_mean_clearance = 0;  // mean encoded clearance (what clearance_change is relative to)
};
[[nodiscard]] std::shared_ptr<Garment> garment_of(GarmentTemplate garment, std::shared_ptr<Family> family);

/// A profile template (immutable; bind_profile.cpp).
struct Template {
  std::shared_ptr<const ProfileTemplate> t;
};
/// The profile templates of a `templates` argument (a ProfileTemplate or a
/// list), copied, each checked to be encoded on `reference` (ValueError
/// naming the template otherwise).
[[nodiscard]] std::vector<ProfileTemplate> profile_templates_arg(py::handle templates, const Body& reference);
/// The region a job's bodies are regenerated in, as `atelier regen` takes
/// it: every node slot of its templates.
[[nodiscard]] Box3d templates_roi(std::span<const ProfileTemplate> templates);

// ------------------------------------------------------------ arrays in

/// An (n, 3) float32 or float64 array (or anything np.asarray makes one of)
/// as doubles, every value finite. Errors name `what` and the row.
[[nodiscard]] std::vector<Vec3d> points_from(py::handle array, const char* what);
/// Faces: an (F, k) integer array (k >= 3), or a sequence of index
/// sequences (polygons of any size), every index in [0, vertex_count).
void faces_into(py::handle faces, std::size_t vertex_count, PolygonSoup& out, const char* what);
/// A mesh argument: a Mesh, a Body, or a (vertices, faces) pair.
[[nodiscard]] std::shared_ptr<const Mesh> mesh_from(py::handle object, const char* what);
/// A mesh argument as a Model to edit: a copy of the Mesh's model, or the
/// soup as one surface "mesh".
[[nodiscard]] Model model_from(py::handle object, const char* what);
/// A soup from vertices and faces (checked as above).
[[nodiscard]] PolygonSoup soup_from(py::handle vertices, py::handle faces, const char* what);

/// A batch of bodies: a (B, n, 3) float32 or float64 array, read in place
/// (any strides). check() runs on the worker thread, without the GIL.
class BodyBatch {
 public:
  BodyBatch(py::handle array, std::size_t node_count, const char* what);
  [[nodiscard]] std::size_t size() const noexcept { return bodies_; }
  [[nodiscard]] std::size_t nodes() const noexcept { return nodes_; }
  /// Every coordinate finite; the error names the body and the vertex.
  [[nodiscard]] Status check(const ExecContext& ctx) const;
  /// Body b as float (the body-set precision) or double.
  void get(std::size_t b, std::vector<Vec3f>& out) const;
  void get(std::size_t b, std::vector<Vec3d>& out) const;
  /// Body b as a span without a copy when its rows are contiguous floats.
  [[nodiscard]] std::span<const Vec3f> floats(std::size_t b) const noexcept;
  [[nodiscard]] std::span<const Vec3d> doubles(std::size_t b) const noexcept;

 private:
  py::array array_;  // keeps the data alive
  const char* what_;
  const char* data_ = nullptr;
  bool is_float_ = false;
  std::size_t bodies_ = 0, nodes_ = 0;
  py::ssize_t stride_[3] = {0, 0, 0};
};

/// The thread count argument (0 = all cores, >= 1).
[[nodiscard]] int threads_arg(int threads);
/// np.float32 or np.float64 (names or numpy dtypes); true for float32.
[[nodiscard]] bool float32_arg(py::handle dtype);

// ------------------------------------------------------------ arrays out

/// A read-only (or writable) view onto memory that `owner` keeps alive.
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, py::handle owner, bool writable = false) {
  py::array a(py::dtype::of<T>(), std::move(shape), {}, data, owner);
  if (!writable) py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}
/// An (n, 3) float64 view onto a Vec3d column.
inline py::array points_view(std::span<const Vec3d> p, py::handle owner, bool writable = false) {
  return view(p.empty() ? nullptr : p.data()->data(), {static_cast<py::ssize_t>(p.size()), 3}, owner, writable);
}
/// An array that owns `v` (moved into a capsule: no copy of the elements).
template <class T>
py::array adopt(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array(py::dtype::of<T>(), std::move(shape), {}, owned->data(), owner);
}
inline py::array adopt_points(std::vector<Vec3d>&& v) {
  auto* owned = new std::vector<Vec3d>(std::move(v));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<Vec3d>*>(p); });
  return py::array(py::dtype::of<double>(), {static_cast<py::ssize_t>(owned->size()), py::ssize_t{3}}, {},
                   owned->empty() ? nullptr : owned->data()->data(), owner);
}
/// Faces of a CSR soup: an (F, k) uint32 view onto face_nodes when every
/// face has k corners, else a list of 1-D arrays (copies).
[[nodiscard]] py::object faces_out(std::span<const std::uint32_t> offsets, std::span<const std::uint32_t> nodes,
                                   py::handle owner);
/// Fan triangles (c0, c_{j+1}, c_{j+2}) of a CSR soup (the engine's corner
/// convention, systems/mesh/fan_triangulation.h).
[[nodiscard]] std::vector<Triangle> fan_triangles(const PolygonSoup& soup);

// ------------------------------------------------------------ long calls

/// Runs work(ctx) on a worker thread with the GIL released; the calling
/// thread waits, and every 25 ms (and when the work ends) takes the GIL to
/// check for signals (a pending SIGINT raises KeyboardInterrupt) and to
/// call `progress(stage, done, total)` with the engine's latest report. On
/// KeyboardInterrupt, or an exception raised by the callback, the engine is
/// cancelled through ctx.cancel, the worker is joined and the Python
/// exception propagates. `work` must not touch Python objects.
template <class F>
auto run_long(const py::object& progress, int threads, F&& work) {
  using R = std::invoke_result_t<F&, const ExecContext&>;
  struct Shared {
    std::mutex m;
    std::condition_variable cv;
    bool finished = false, fresh = false;
    std::string stage;
    std::size_t done = 0, total = 0;
  };
  auto sh = std::make_shared<Shared>();
  ExecContext ctx;
  ctx.threads = threads_arg(threads);
  ctx.progress = [sh](std::string_view stage, std::size_t done, std::size_t total) {
    const std::lock_guard<std::mutex> lock(sh->m);
    sh->stage.assign(stage);
    sh->done = done;
    sh->total = total;
    sh->fresh = true;
  };
  const bool has_callback = progress && !progress.is_none();
  std::conditional_t<std::is_void_v<R>, bool, std::optional<R>> result{};
  std::exception_ptr error;
  std::optional<py::error_already_set> py_error;
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        if constexpr (std::is_void_v<R>) {
          work(std::as_const(ctx));
          result = true;
        } else {
          result.emplace(work(std::as_const(ctx)));
        }
      } catch (...) {
        error = std::current_exception();
      }
      {
        const std::lock_guard<std::mutex> lock(sh->m);
        sh->finished = true;
      }
      sh->cv.notify_all();
    });
    for (;;) {
      std::unique_lock<std::mutex> lock(sh->m);
      sh->cv.wait_for(lock, std::chrono::milliseconds(25), [&] { return sh->finished; });
      const bool finished = sh->finished, fresh = sh->fresh;
      const std::string stage = sh->stage;
      const std::size_t done = sh->done, total = sh->total;
      sh->fresh = false;
      lock.unlock();
      if (!py_error) {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          py_error.emplace();
          ctx.cancel.cancel();
        } else if (fresh && has_callback) {
          try {
            progress(stage, done, total);
          } catch (py::error_already_set& e) {
            py_error.emplace(std::move(e));
            ctx.cancel.cancel();
          }
        }
      }
      if (finished) break;
    }
    worker.join();
  }
  if (py_error) throw std::move(*py_error);
  if (error) std::rethrow_exception(error);
  if constexpr (!std::is_void_v<R>) return std::move(*result);
}

// ------------------------------------------------------------ the families

void bind_io(py::module_& m);
void bind_body(py::module_& m);
void bind_garment(py::module_& m);
void bind_regenerate(py::module_& m);
void bind_profile(py::module_& m);
void bind_view(py::module_& m);
void bind_net(py::module_& m);
void bind_curvenet(py::module_& m);
void bind_pattern(py::module_& m);
void bind_sketch(py::module_& m);

}  // namespace atelier::python

#define ATELIER_PY_NAME(Name, Text)                                  \
  template <>                                                        \
  struct pybind11::detail::handle_type_name<atelier::python::Name> { \
    static constexpr auto name = pybind11::detail::const_name(Text); \
  };
ATELIER_PY_NAME(Array, "numpy.ndarray")
ATELIER_PY_NAME(OptArray, "numpy.ndarray | None")
ATELIER_PY_NAME(Faces, "numpy.ndarray | list[list[int]]")
ATELIER_PY_NAME(OptFaces, "numpy.ndarray | list[list[int]] | None")
ATELIER_PY_NAME(Progress, "Callable[[str, int, int], None] | None")
ATELIER_PY_NAME(DType, "numpy.dtype | str")
ATELIER_PY_NAME(Params, "dict | list[dict] | numpy.ndarray | None")
ATELIER_PY_NAME(MeshLike, "Mesh | Body | tuple[numpy.ndarray, numpy.ndarray]")
ATELIER_PY_NAME(OptMeshLike, "Mesh | Body | tuple[numpy.ndarray, numpy.ndarray] | None")
ATELIER_PY_NAME(MeshOrArray, "Mesh | Body | numpy.ndarray")
ATELIER_PY_NAME(MeshList, "Mesh | tuple[numpy.ndarray, numpy.ndarray] | list | None")
ATELIER_PY_NAME(GarmentSource, "numpy.ndarray | Mesh | os.PathLike")
ATELIER_PY_NAME(Garments, "GarmentTemplate | list[GarmentTemplate]")
ATELIER_PY_NAME(Templates, "ProfileTemplate | list[ProfileTemplate]")
ATELIER_PY_NAME(Colours, "list[tuple[float, float, float]] | None")
ATELIER_PY_NAME(Colour, "tuple[float, float, float] | None")
ATELIER_PY_NAME(CurveName, "str | int")
ATELIER_PY_NAME(NDArray, "numpy.ndarray")
ATELIER_PY_NAME(Curves, "list[numpy.ndarray] | os.PathLike")
ATELIER_PY_NAME(Strokes, "dict | os.PathLike")
#undef ATELIER_PY_NAME
