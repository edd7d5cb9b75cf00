// Level sets (voxfx/level_set.hpp): voxfx.LevelSet (an OpenVDB FloatGrid of class level set), read
// and made from meshes or signed distance fields, CSG with level sets and meshes (a mesh joins on
// the level set's lattice: exact), and offsets.
#include "voxfx/level_set.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <variant>

#include <unistd.h>

#include "common.hpp"
#include "voxfx/sdf.hpp"

namespace voxfx::python {
namespace {

using LevelSetPtr = std::shared_ptr<LevelSet>;
using SdfPtr = std::shared_ptr<SignedDistanceField>;

void checkThreads(int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
}

/// A CSG operand: a voxfx.LevelSet, or anything meshArgument accepts.
struct Operand {
    LevelSetPtr set;
    std::shared_ptr<PyMesh> mesh;
};

Operand operand(const py::object& o, const char* name) {
    if (py::isinstance<LevelSet>(o)) return {o.cast<LevelSetPtr>(), nullptr};
    if (o.is_none())
        throw py::type_error(std::string(name) + " is None; expected a voxfx.LevelSet or a mesh");
    Operand r{nullptr, meshArgument(o, py::none())};
    asArgument([&] { validateMesh(r.mesh->mesh.view(), name); });
    return r;
}

/// The level set of a mesh on `lattice`'s lattice (levelSetOfMesh), without the GIL, stoppable by
/// Ctrl-C. Called with the GIL released.
LevelSet onLattice(const PyMesh& mesh, const LevelSet& lattice, Fill fill, Cancel& cancel) {
    SdfOptions o;
    o.fill = fill;
    o.progress = &cancel;
    return levelSetOfMesh(mesh.mesh.view(), lattice, o, mesh.origin);
}

/// a op b where each is a level set or a mesh (at least one a level set: the lattice, a's when
/// both are). Warns (RuntimeWarning) when b had to be resampled onto a's lattice.
LevelSetPtr combine(const py::object& aObj, const py::object& bObj, CsgOp op, const std::string& fillName,
                    int threads) {
    checkThreads(threads);
    const Fill fill = asArgument([&] { return parseFill(fillName); });
    const Operand a = operand(aObj, "a"), b = operand(bObj, "b");
    if (!a.set && !b.set)
        throw ArgumentError(
            "level-set CSG needs a voxfx.LevelSet among its operands (both are meshes: make one "
            "with voxfx.level_set(mesh, ...))");
    LevelSetPtr out;
    bool resampled = false;
    interruptible([&](Cancel& cancel) {
        withThreads(threads, [&] {
            const LevelSet& lattice = a.set ? *a.set : *b.set;
            const LevelSet ma = a.set ? LevelSet() : onLattice(*a.mesh, lattice, fill, cancel);
            const LevelSet mb = b.set ? LevelSet() : onLattice(*b.mesh, lattice, fill, cancel);
            out = std::make_shared<LevelSet>(
                levelSetCsg(a.set ? *a.set : ma, b.set ? *b.set : mb, op, &resampled));
        });
    });
    if (resampled &&
        PyErr_WarnEx(PyExc_RuntimeWarning,
                     "voxfx: the second level set lies on another lattice and was resampled onto the "
                     "first's (OpenVDB's resampleToMatch: a level-set rebuild, approximate within "
                     "about a voxel)",
                     1) != 0)
        throw py::error_already_set(); // the warning was turned into an exception
    return out;
}

/// (N, 3) integer indices (or one (3,) index) as int32 triples; TypeError for other dtypes or
/// shapes, ArgumentError for an index beyond OpenVDB's int32 coordinates.
std::vector<std::array<int32_t, 3>> indexArgument(const py::object& obj, bool& single) {
    const py::array arr = py::array::ensure(obj);
    if (!arr) throw py::type_error("indices: expected an (N, 3) integer array");
    const char kind = arr.dtype().kind();
    if (kind != 'i' && kind != 'u' && !(arr.size() == 0 && kind == 'f'))
        throw py::type_error(std::string("indices: expected an integer array (voxel indices), got dtype ") +
                             std::string(py::str(arr.dtype())));
    single = arr.ndim() == 1;
    if (!((arr.ndim() == 2 && arr.shape(1) == 3) || (arr.ndim() == 1 && arr.shape(0) == 3)))
        throw py::type_error("indices: expected an (N, 3) array or one (3,) index");
    const auto ijk = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(arr);
    if (!ijk) throw py::type_error("indices: cannot be read as 64-bit integers");
    const int64_t* p = ijk.data();
    const std::size_t n = std::size_t(ijk.size() / 3);
    std::vector<std::array<int32_t, 3>> out(n);
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const int64_t v = p[3 * i + std::size_t(a)];
            if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max())
                throw ArgumentError("indices: " + std::to_string(v) +
                                    " lies beyond OpenVDB's 32-bit indices");
            out[i][std::size_t(a)] = int32_t(v);
        }
    return out;
}

py::object values(const LevelSet& ls, const py::object& indices) {
    bool single = false;
    const std::vector<std::array<int32_t, 3>> ijk = indexArgument(indices, single);
    py::array_t<float> out(py::ssize_t(ijk.size()));
    {
        float* o = out.mutable_data();
        py::gil_scoped_release release;
        ls.values(ijk, std::span<float>(o, ijk.size()));
    }
    if (single) return py::float_(out.at(0));
    return out;
}

py::tuple activeVoxels(const LevelSet& ls) {
    return activeVoxelArrays([&](auto& indices, auto& values) { ls.activeVoxels(indices, values); });
}

/// 4 x 4 matrix from (i, j, k, 1) to the world centre of index (i, j, k) (axis-aligned lattices).
py::array_t<double> levelSetAffine(const LevelSet& ls) {
    if (!ls.axisAligned())
        throw Error("level set '" + ls.name() +
                    "': its transform is not a positive scale and a translation, so no affine is given");
    const Vec3d vs = ls.voxelSize(), c0 = ls.indexOrigin();
    py::array_t<double> a({py::ssize_t(4), py::ssize_t(4)});
    double* p = a.mutable_data();
    std::fill(p, p + 16, 0.0);
    for (int k = 0; k < 3; ++k) {
        p[5 * k] = vs[k];
        p[4 * k + 3] = c0[k];
    }
    p[15] = 1;
    return a;
}

void save(const LevelSet& ls, const py::object& pathObj) {
    const std::string path = pathString(pathObj);
    py::gil_scoped_release release;
    writeLevelSet(ls, path);
}

std::string repr(const LevelSet& ls) {
    std::ostringstream s;
    s << "<voxfx.LevelSet '" << ls.name() << "', voxel " << ls.voxelSize().x << ", band " << ls.bandVoxels()
      << " voxels (" << ls.background() << "), " << ls.activeCount() << " active>";
    return s.str();
}

/// voxfx.level_set: from a SignedDistanceField, a mesh on a grid fitted as sdf() fits it, or a mesh
/// on another level set's lattice (like=).
LevelSetPtr makeLevelSet(const py::object& meshObj, const py::object& faces, const py::object& like,
                         std::optional<int64_t> resolution, std::optional<double> voxelSize,
                         const py::object& bounds, std::optional<int64_t> margin, bool cube,
                         std::optional<double> band, const std::string& fill, const std::string& name,
                         int threads) {
    checkThreads(threads);
    const bool fitting = resolution || voxelSize || !bounds.is_none() || margin || cube || band;
    if (py::isinstance<SignedDistanceField>(meshObj)) {
        if (!faces.is_none() || !like.is_none() || fitting || fill != "auto")
            throw ArgumentError(
                "level_set(field) takes the field's grid, band and sign as they are: no other "
                "argument but name");
        const SdfPtr field = meshObj.cast<SdfPtr>();
        py::gil_scoped_release release;
        return std::make_shared<LevelSet>(asArgument([&] { return LevelSet::fromField(*field, name); }));
    }
    if (!like.is_none()) {
        if (!py::isinstance<LevelSet>(like)) throw py::type_error("like: expected a voxfx.LevelSet");
        if (fitting)
            throw ArgumentError(
                "like= puts the mesh on that level set's lattice, with its voxel size and band: "
                "resolution, voxel_size, bounds, margin, cube and band do not apply");
        const Fill f = asArgument([&] { return parseFill(fill); });
        const LevelSetPtr lattice = like.cast<LevelSetPtr>();
        const auto mesh = meshArgument(meshObj, faces);
        asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
        LevelSetPtr out;
        interruptible([&](Cancel& cancel) {
            withThreads(threads,
                        [&] { out = std::make_shared<LevelSet>(onLattice(*mesh, *lattice, f, cancel)); });
        });
        return out;
    }
    const SdfPtr field = makeSdf(meshObj, faces, resolution, voxelSize, bounds, margin, cube,
                                 band.value_or(3.0), fill, threads);
    py::gil_scoped_release release;
    return std::make_shared<LevelSet>(LevelSet::fromField(*field, name));
}

/// A file name in the temporary folder no other call uses (pid, a counter, the time).
std::string scratchPath(const char* suffix) {
    static std::atomic<uint64_t> counter{0};
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    return (std::filesystem::temp_directory_path() /
            ("voxfx-pickle-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
             std::to_string(stamp) + suffix))
        .string();
}

/// Pickle state: version and the .vdb file's bytes (the grid with its transform, class and name:
/// OpenVDB's own serialization, written through a scratch file removed at once).
py::tuple levelSetState(const LevelSet& l) {
    const std::string path = scratchPath(".vdb");
    std::string bytes;
    {
        py::gil_scoped_release release;
        writeLevelSet(l, path);
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
        std::filesystem::remove(path);
    }
    return py::make_tuple(1, py::bytes(bytes));
}

LevelSetPtr levelSetFromState(const py::tuple& t) {
    if (t.size() != 2 || t[0].cast<int>() != 1)
        throw py::value_error("not a voxfx.LevelSet pickle (version 1)");
    const std::string bytes = t[1].cast<std::string>();
    const std::string path = scratchPath(".vdb");
    py::gil_scoped_release release;
    {
        std::ofstream out(path, std::ios::binary);
        out.write(bytes.data(), std::streamsize(bytes.size()));
    }
    try {
        auto l = std::make_shared<LevelSet>(readLevelSet(path));
        std::filesystem::remove(path);
        return l;
    } catch (...) {
        std::filesystem::remove(path);
        throw;
    }
}

/// offsetLevelSet, clamped and stoppable. Inwards beyond the active voxels' extent (plus the band)
/// the level set is empty whatever the distance: clamped there, as dense morphology clamps its
/// radius. Outwards the band grows with the surface's area: refused up front (MemoryLimitError)
/// when that area's band would not fit in the memory available. Offsets of more than 8 voxels run
/// 8 voxels at a time, Ctrl-C polled between.
LevelSetPtr offsetClamped(const LevelSet& l, double distance, int threads) {
    const Vec3d vs = l.voxelSize();
    Vec3i lo, hi;
    l.activeBounds(lo, hi);
    const double voxel = std::max({vs.x, vs.y, vs.z});
    if (lo.x <= hi.x && voxel > 0) {
        double extent = 0;
        for (int a = 0; a < 3; ++a) extent = std::max(extent, double(hi[a] - lo[a] + 1) * vs[a]);
        const double reach = extent + 2 * double(l.background()) + voxel;
        if (distance < -reach) distance = -reach;
        if (distance > 0) {
            // The band's voxels scale with the area: (r + d)^2 / r^2 over a sphere of radius r.
            const double r = std::max(0.5 * extent, voxel);
            const double grow = (r + distance) / r;
            const double bytes = double(l.activeCount()) * grow * grow * 8.0;
            const uint64_t available = availableMemoryBytes();
            if (bytes > double(available))
                throw MemoryLimitError(detail::concat(
                    "offset_level_set: an offset of ", distance, " (", distance / voxel,
                    " voxels) grows the band to about ", uint64_t(std::min(bytes, 0x1p63)) >> 20,
                    " MiB, but only ", available >> 20, " MiB of memory is available"));
        }
    }
    LevelSetPtr out;
    interruptible([&](Cancel& cancel) {
        withThreads(threads, [&] {
            const double step = 8 * voxel;
            LevelSet cur = l;
            double left = distance;
            while (std::abs(left) > step && step > 0) {
                const double d = left > 0 ? step : -step;
                cur = offsetLevelSet(cur, d);
                left -= d;
                if (cancel.requested()) fail("cancelled");
            }
            out = std::make_shared<LevelSet>(offsetLevelSet(cur, left));
        });
    });
    return out;
}

using LevelSetClass = py::class_<LevelSet, LevelSetPtr>;

/// voxfx.LevelSet's properties, queries, pickling and files.
void bindLevelSetQueries(LevelSetClass& ls) {
    ls.def_property_readonly(
          "voxel_size", [](const LevelSet& l) { return vec3(l.voxelSize()); },
          "World size of a voxel along the index axes")
        .def_property_readonly("background", &LevelSet::background,
                               "The band's half-width in world units: inactive voxels hold +background or "
                               "-background")
        .def_property_readonly("band", &LevelSet::bandVoxels, "The band's half-width in voxels")
        .def_property_readonly(
            "index_origin", [](const LevelSet& l) { return vec3(l.indexOrigin()); },
            "World position of index (0, 0, 0)")
        .def_property_readonly("axis_aligned", &LevelSet::axisAligned,
                               "Whether index (i, j, k) lies at index_origin + (i, j, k) * voxel_size")
        .def_property_readonly("affine", &levelSetAffine,
                               "4 x 4 matrix from (i, j, k, 1) to the world position of index (i, j, k) "
                               "(axis-aligned level sets; voxfx.Error otherwise)")
        .def(py::pickle(&levelSetState, &levelSetFromState))
        .def_property_readonly("active_count", &LevelSet::activeCount)
        .def_property_readonly(
            "active_bounds",
            [](const LevelSet& l) -> py::object {
                Vec3i lo, hi;
                l.activeBounds(lo, hi);
                if (lo.x > hi.x) return py::none();
                return py::make_tuple(vec3(lo), vec3(hi));
            },
            "(lo, hi): the active voxels' index box, inclusive; None when there is none")
        .def_property_readonly("name", &LevelSet::name)
        .def("active_voxels", &activeVoxels,
             "(indices (N, 3) int32, values (N,) float32) of the active voxels, in the tree's order")
        .def("value", &values, py::arg("indices"),
             "The values at integer indices: an (N, 3) array gives (N,) float32, one (3,) index a float; any "
             "index (+-background away from the band)")
        .def("save", &save, py::arg("path"), "Writes the level set as a .vdb file (atomically)")
        .def("write", &save, py::arg("path"), "save(), under the name of voxfx::writeLevelSet");
}

/// voxfx.LevelSet's CSG (methods and operators, a mesh on either side) and copies.
void bindLevelSetCsg(LevelSetClass& ls) {
    ls.def(
          "union",
          [](const py::object& self, const py::object& other, const std::string& fill, int threads) {
              return combine(self, other, CsgOp::Union, fill, threads);
          },
          py::arg("other"), py::kw_only(), py::arg("fill") = "auto", py::arg("threads") = 0,
          "level_set_csg(self, other, 'union')")
        .def(
            "intersection",
            [](const py::object& self, const py::object& other, const std::string& fill, int threads) {
                return combine(self, other, CsgOp::Intersection, fill, threads);
            },
            py::arg("other"), py::kw_only(), py::arg("fill") = "auto", py::arg("threads") = 0,
            "level_set_csg(self, other, 'intersection')")
        .def(
            "difference",
            [](const py::object& self, const py::object& other, const std::string& fill, int threads) {
                return combine(self, other, CsgOp::Difference, fill, threads);
            },
            py::arg("other"), py::kw_only(), py::arg("fill") = "auto", py::arg("threads") = 0,
            "level_set_csg(self, other, 'difference')")
        .def(
            "__or__",
            [](const py::object& self, const py::object& other) {
                return combine(self, other, CsgOp::Union, "auto", 0);
            },
            py::is_operator())
        .def(
            "__and__",
            [](const py::object& self, const py::object& other) {
                return combine(self, other, CsgOp::Intersection, "auto", 0);
            },
            py::is_operator())
        .def(
            "__sub__",
            [](const py::object& self, const py::object& other) {
                return combine(self, other, CsgOp::Difference, "auto", 0);
            },
            py::is_operator())
        // A mesh on the left (mesh | level_set): Python asks the level set on the right.
        .def(
            "__ror__",
            [](const py::object& self, const py::object& other) {
                return combine(other, self, CsgOp::Union, "auto", 0);
            },
            py::is_operator())
        .def(
            "__rand__",
            [](const py::object& self, const py::object& other) {
                return combine(other, self, CsgOp::Intersection, "auto", 0);
            },
            py::is_operator())
        .def(
            "__rsub__",
            [](const py::object& self, const py::object& other) {
                return combine(other, self, CsgOp::Difference, "auto", 0);
            },
            py::is_operator())
        .def("copy", [](const LevelSet& l) { return std::make_shared<LevelSet>(l); })
        .def("__copy__", [](const LevelSet& l) { return std::make_shared<LevelSet>(l); })
        .def(
            "__deepcopy__",
            [](const LevelSet& l, const py::object&) { return std::make_shared<LevelSet>(l); },
            py::arg("memo"))
        .def("__repr__", &repr);
}

/// The module's level set functions: read, make, CSG, offset.
void bindLevelSetFunctions(py::module_& m) {
    m.def(
        "read_level_set",
        [](const py::object& pathObj) {
            const std::string path = pathString(pathObj);
            py::gil_scoped_release release;
            return std::make_shared<LevelSet>(readLevelSet(path));
        },
        py::arg("path"),
        "Reads the first grid of a .vdb file, which must be a FloatGrid of class level set (voxfx.Error "
        "saying "
        "what it is otherwise)");
    m.def(
        "level_set", &makeLevelSet, py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(),
        py::arg("like") = py::none(), py::arg("resolution") = py::none(), py::arg("voxel_size") = py::none(),
        py::arg("bounds") = py::none(), py::arg("margin") = py::none(), py::arg("cube") = false,
        py::arg("band") = py::none(), py::arg("fill") = "auto", py::arg("name") = "sdf",
        py::arg("threads") = 0,
        "A level set of a mesh: its exact signed distance field as voxfx.sdf() computes it (the same grid "
        "fitting; band in voxels, default 3), as an OpenVDB level set named `name` whose index (i, j, k) is "
        "voxel (i, j, k). With like=a_level_set the mesh is put on that level set's lattice instead (its "
        "voxel centres, band and transform; cubic axis-aligned voxels), so CSG with it is exact. A "
        "voxfx.SignedDistanceField (narrow band) becomes a level set as it is. The GIL is released; Ctrl-C "
        "stops it.");
    m.def(
        "level_set_csg",
        [](const py::object& a, const py::object& b, const std::string& op, const std::string& fill,
           int threads) {
            const CsgOp o = asArgument([&] { return parseCsgOp(op); });
            return combine(a, b, o, fill, threads);
        },
        py::arg("a"), py::arg("b"), py::arg("op") = "union", py::kw_only(), py::arg("fill") = "auto",
        py::arg("threads") = 0,
        "a op b (union, intersection, difference, xor) of level sets by OpenVDB's csgUnion, csgIntersection "
        "and csgDifference: voxel by voxel min(a, b), max(a, b), max(a, -b). Either operand may be a mesh: "
        "its exact signed distance field on the level set's lattice (fill: the mesh's inside test), so "
        "nothing is resampled and the result is exact (the sign exactly the combined solid's; the value the "
        "exact distance except near the creases where the surfaces meet, where it is a lower bound). Two "
        "level sets on different lattices: b is resampled onto a's (approximate; a RuntimeWarning says so). "
        "The result has the lattice, band and name of a (of the level set, when a is a mesh).");
    m.def(
        "offset_level_set",
        [](const LevelSet& l, double distance, Int threads) {
            checkThreads(int(threads));
            if (!std::isfinite(distance)) throw ArgumentError("distance must be finite");
            return offsetClamped(l, distance, int(threads));
        },
        py::arg("level_set"), py::arg("distance"), py::kw_only(), py::arg("threads") = 0,
        "OpenVDB's LevelSetFilter::offset: the surface moves `distance` world units outwards (inwards when "
        "negative); approximate (the tracker's finite differences, about a twentieth of a voxel on a "
        "sphere). Needs cubic voxels. The exact offset of a mesh's field is `voxfx sdf --offset`. Inward "
        "offsets beyond the level set's extent are clamped (the result is empty); outward ones whose band "
        "cannot fit raise voxfx.MemoryLimitError up front. The GIL is released; Ctrl-C stops it.");
}

} // namespace

void bindLevelSet(py::module_& m) {
    LevelSetClass ls(
        m, "LevelSet",
        "A narrow-band level set: an OpenVDB FloatGrid of class level set (signed distances in world units, "
        "negative inside, active within the band, +-background beyond) with its own index-to-world "
        "transform. "
        "Read with voxfx.read_level_set, made with voxfx.level_set, combined with voxfx.level_set_csg (or | "
        "& "
        "-) and offset with voxfx.offset_level_set. A value: operations return new level sets.");
    bindLevelSetQueries(ls);
    bindLevelSetCsg(ls);
    bindLevelSetFunctions(m);
}

} // namespace voxfx::python
