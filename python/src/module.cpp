// The extension module atelier._atelier (issue 25; docs/python.md): one
// source per family binds its calls. A family that lands later adds
// bind_<family>.cpp with `void bind_<family>(py::module_&)`, declares it in
// bind.h and calls it here.
#include "bind.h"

PYBIND11_MODULE(_atelier, m) {
  m.doc() = R"doc(Atelier: bodies, garments and templates as numpy arrays.

The Python binding of the Atelier geometry engine (docs/python.md): sample
mannequins and MakeHuman bodies, encode garments on a reference body and
regenerate them on batches of bodies given as (B, n, 3) arrays, regenerate
profile templates, read and write meshes, render pictures.

Long calls release the GIL, take ``threads`` (0 = all cores; results do not
depend on it) and an optional ``progress(stage, done, total)`` callback, and
stop on Ctrl-C (KeyboardInterrupt) through the engine's cancellation.
Engine errors raise OSError (files) or ValueError (bad input) with the
engine's message.
)doc";
  namespace py = pybind11;
  using namespace atelier::python;
  register_errors(m);
  bind_io(m);
  bind_body(m);
  bind_garment(m);
  bind_regenerate(m);
  bind_profile(m);
  bind_view(m);
  bind_net(m);
  bind_curvenet(m);
  bind_pattern(m);
  bind_sketch(m);
  m.attr("__version__") = ATELIER_VERSION_STRING;
}
