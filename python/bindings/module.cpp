// voxfx Python module (voxfx._voxfx): meshes, voxelization, grids as NumPy arrays, the grid
// toolkit and exact point occupancy, over the public C++ API only. This file makes the module,
// its exception types and their translator; each area of the library binds itself in its own
// file, in the order areas.inc lists them.
#include <exception>

#include "common.hpp"

namespace py = pybind11;
using namespace voxfx;

PYBIND11_MODULE(_voxfx, m) {
    m.doc() = "voxfx: voxelization of triangle meshes into bit grids (slicemaps), with NumPy arrays";
    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    error.attr("__module__") = "voxfx";
    // Bad arguments: a voxfx.Error that is also a ValueError (except ValueError catches them).
    // A handle the module owns (the type lives as long as the module; no destructor at exit).
    static py::handle argumentError = PyErr_NewExceptionWithDoc(
        "voxfx.ArgumentError",
        "A bad argument (a name, a size, a path): both a voxfx.Error and a ValueError.",
        py::make_tuple(error, py::handle(PyExc_ValueError)).ptr(), nullptr);
    if (!argumentError) throw py::error_already_set();
    m.attr("ArgumentError") = argumentError;
    // Refusals for want of memory (a size checked before allocating, a budget outgrown): a
    // voxfx.Error that is also a MemoryError (except MemoryError catches them).
    static py::handle memoryLimitError = PyErr_NewExceptionWithDoc(
        "voxfx.MemoryLimitError",
        "A refusal for want of memory (the size checked before allocating against the memory available, "
        "the cgroup's limit or VOXFX_MEMORY_LIMIT): both a voxfx.Error and a MemoryError.",
        py::make_tuple(error, py::handle(PyExc_MemoryError)).ptr(), nullptr);
    if (!memoryLimitError) throw py::error_already_set();
    m.attr("MemoryLimitError") = memoryLimitError;
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const python::ArgumentError& e) {
            PyErr_SetObject(argumentError.ptr(), python::utf8Text(e.what()).ptr());
        } catch (const MemoryLimitError& e) {
            PyErr_SetObject(memoryLimitError.ptr(), python::utf8Text(e.what()).ptr());
        } catch (const Error& e) {
            // Messages quote file contents, which need not be UTF-8: invalid bytes are replaced
            // (PyErr_SetString would raise UnicodeDecodeError instead of voxfx.Error).
            const py::str message = python::utf8Text(e.what());
            PyErr_SetObject(error.ptr(), message.ptr());
        }
    });

#define VOXFX_PYTHON_AREA(Area) python::bind##Area(m);
#include "areas.inc"
#undef VOXFX_PYTHON_AREA

    m.attr("__version__") = VOXFX_VERSION_STRING;
}
