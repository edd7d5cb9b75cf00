// voxfx — voxelization driver: surface (ED06 §2), solid by parity (GI08 §4), conservative and
// interior variants (GI08 §5), robust fills for open meshes, and frame fitting.
#include "voxfx/voxelize.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <limits>

#include "voxelize/consumers.hpp"
#include "voxelize/fill.hpp"
#include "voxelize/winding_tree.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

namespace {

// Every pass of a voxelization that needs the inside sees each column's whole line in a
// perspective frame (RasterOptions::fullLine: parity and winding count crossings behind the eye
// too), so that its passes clip alike, as the CUDA back end's do (CudaVoxelizer::voxelize).
RasterOptions passOptions(const VoxelizeOptions& o) {
    RasterOptions ro;
    ro.progress = o.progress;
    ro.path = o.rasterPath;
    ro.fullLine = needsFill(o.mode);
    return ro;
}

// Clears the cells within `ring` of every side (VoxelizeOptions::emptyBorder).
void clearBorder(BitGrid& g, int64_t ring) {
    if (ring <= 0 || g.empty()) return;
    const int64_t W = g.width(), H = g.height(), D = g.depth(), P = g.wordsPerColumn();
    parallelFor(0, W * H, 1024, [&](int64_t c0, int64_t c1) {
        for (int64_t c = c0; c < c1; ++c) {
            const int64_t x = c % W, y = c / W;
            uint64_t* col = g.column(x, y);
            if (x < ring || x >= W - ring || y < ring || y >= H - ring) {
                std::fill(col, col + P, uint64_t(0));
                continue;
            }
            for (int64_t s = 0; s < std::min(ring, D); ++s) col[s >> 6] &= ~(uint64_t(1) << (s & 63));
            for (int64_t s = std::max<int64_t>(0, D - ring); s < D; ++s)
                col[s >> 6] &= ~(uint64_t(1) << (s & 63));
        }
    });
}

// The padding ring of `o` in `frame` (VoxelizeOptions::emptyBorder): 0 where it does not apply.
int64_t paddingRing(const Frame& frame, const VoxelizeOptions& o) {
    const bool grid = !frame.isPerspective() && !frame.isOriented() && frame.slicing() == Slicing::Uniform &&
                      o.slicing == Slicing::Uniform;
    return grid ? std::max<int64_t>(0, o.emptyBorder) : 0;
}

BitGrid rasterizeInto(const Frame& frame, const MeshView& mesh, VoxelizeMode kind, const VoxelizeOptions& o) {
    BitGrid grid(frame.width(), frame.height(), frame.depth());
    const RasterOptions ro = passOptions(o);
    switch (kind) {
    case VoxelizeMode::Surface: {
        detail::SurfaceConsumer c{frame.view(), grid.view()};
        rasterize<Coverage::Center>(frame, mesh, ro, c);
        break;
    }
    case VoxelizeMode::Conservative: {
        detail::ConservativeConsumer c{frame.view(), grid.view()};
        rasterize<Coverage::Conservative>(frame, mesh, ro, c);
        break;
    }
    default:
        VOXFX_CHECK(false);
    }
    // Surface cells in the padding ring are dropped: they would wall the border off from a flood.
    clearBorder(grid, paddingRing(frame, o));
    return grid;
}

void requireUniformOrthographic(const Frame& frame, Fill fill) {
    if (frame.isPerspective() || frame.isOriented() || frame.slicing() != Slicing::Uniform)
        fail("fill '", toString(fill), "' needs an axis-aligned orthographic frame with uniform slicing");
}

// Inside cells by the requested fill. Flood includes the surface cells.
BitGrid fillInside(const Frame& frame, const MeshView& mesh, const VoxelizeOptions& o,
                   const BitGrid* surface) {
    const RasterOptions ro = passOptions(o);
    switch (o.fill) {
    case Fill::Parity: {
        BitGrid grid(frame.width(), frame.height(), frame.depth());
        detail::ParityConsumer c{frame.view(), grid.view()};
        rasterize<Coverage::Center>(frame, mesh, ro, c);
        return grid;
    }
    case Fill::Winding: {
        BitGrid grid(frame.width(), frame.height(), frame.depth());
        detail::WindingConsumer c{frame.view(), grid.view()};
        rasterize<Coverage::Center>(frame, mesh, ro, c);
        return grid;
    }
    case Fill::Flood: {
        requireUniformOrthographic(frame, o.fill);
        BitGrid walls = surface ? *surface : rasterizeInto(frame, mesh, VoxelizeMode::Conservative, o);
        return detail::floodFillInside(walls);
    }
    case Fill::Gwn: {
        // Barill et al.'s beta 2: dipole error about 0.05 at worst, far below the 0.5 threshold's
        // margin except where the winding number is near 0.5 anyway (holes).
        const BitGrid walls = surface ? BitGrid() : rasterizeInto(frame, mesh, VoxelizeMode::Conservative, o);
        detail::WindingTree tree;
        tree.build(mesh, 2.0);
        return detail::gwnFillInside(frame, mesh, tree, surface ? *surface : walls, o.progress);
    }
    case Fill::Vote: {
        requireUniformOrthographic(frame, o.fill);
        VoxelizeOptions parity = o;
        parity.fill = Fill::Parity;
        parity.mode = VoxelizeMode::Solid;
        parity.report = nullptr; // the caller's report says "vote", not the three parities
        const VoxelGrid votes[3] = {
            {frame, fillInside(frame, mesh, parity, nullptr)},
            reslice(voxelize(mesh, detail::reframe(frame, Axis((int(frame.axis()) + 1) % 3)), parity),
                    frame.axis()),
            reslice(voxelize(mesh, detail::reframe(frame, Axis((int(frame.axis()) + 2) % 3)), parity),
                    frame.axis())};
        return detail::majority(votes[0].bits, votes[1].bits, votes[2].bits);
    }
    case Fill::Auto:
        break; // resolveFill replaced it before
    }
    VOXFX_CHECK(false);
    return {};
}

void combine(BitGrid& a, const BitGrid& b, bool andNot) {
    uint64_t* pa = a.words();
    const uint64_t* pb = b.words();
    parallelFor(0, a.wordCount(), int64_t(1) << 16, [&](int64_t s, int64_t e) {
        if (andNot)
            for (int64_t i = s; i < e; ++i) pa[i] &= ~pb[i];
        else
            for (int64_t i = s; i < e; ++i) pa[i] |= pb[i];
    });
}

VoxelGrid voxelizeImpl(const MeshView& mesh, const Frame& inFrame, const VoxelizeOptions& o);

// voxelizeImpl with the padding ring kept empty (see VoxelizeOptions::emptyBorder).
VoxelGrid voxelizePadded(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& o) {
    VoxelGrid g = voxelizeImpl(mesh, frame, o);
    clearBorder(g.bits, paddingRing(frame, o));
    return g;
}

VoxelGrid voxelizeImpl(const MeshView& mesh, const Frame& inFrame, const VoxelizeOptions& o) {
    Frame frame = inFrame;
    if (o.slicing == Slicing::Local) {
        // ED06 fig. 2: a first pass records each column's nearest and farthest geometry, then the
        // D slices spread over that range only. Conservative coverage when the mode needs spans.
        std::vector<double> nearDepth(size_t(frame.columnCount()), std::numeric_limits<double>::infinity());
        std::vector<double> farDepth(size_t(frame.columnCount()), -std::numeric_limits<double>::infinity());
        detail::DepthRangeConsumer c{frame.width(), nearDepth, farDepth};
        RasterOptions ro;
        ro.coverage = o.mode == VoxelizeMode::Surface ? Coverage::Center : Coverage::Conservative;
        rasterize(frame, mesh, ro, c);
        frame.setLocalSlicing(nearDepth, farDepth);
    }
    const bool needsSurface = o.mode != VoxelizeMode::Solid || o.fill == Fill::Flood || o.fill == Fill::Gwn;
    const uint64_t grids =
        needsSurface && o.mode != VoxelizeMode::Surface && o.mode != VoxelizeMode::Conservative ? 2 : 1;
    checkMemory(grids * BitGrid::requiredBytes(frame.width(), frame.height(), frame.depth()),
                "voxelization at this resolution");

    if (o.deviceNote) o.deviceNote->clear();
    if (o.device != Device::Cpu) {
        std::string why;
        if (!cudaStatus().available) {
            why = cudaStatus().reason;
        } else if (o.mode != VoxelizeMode::Surface && o.mode != VoxelizeMode::Conservative &&
                   o.fill != Fill::Parity) {
            why = detail::concat("fill '", toString(o.fill), "' has no CUDA version yet (parity has)");
        } else {
            try {
                CudaVoxelizer gpu;
                gpu.setMesh(mesh);
                gpu.voxelize(frame, o.mode);
                return {frame, gpu.download()};
            } catch (const Error& e) { why = e.what(); }
        }
        if (o.deviceNote) *o.deviceNote = detail::concat(why, "; voxelized on the CPU");
    }

    switch (o.mode) {
    case VoxelizeMode::Surface:
    case VoxelizeMode::Conservative:
        return {frame, rasterizeInto(frame, mesh, o.mode, o)};
    case VoxelizeMode::Solid:
        return {frame, fillInside(frame, mesh, o, nullptr)};
    case VoxelizeMode::SolidConservative:
    case VoxelizeMode::Interior: {
        BitGrid surface = rasterizeInto(frame, mesh, VoxelizeMode::Conservative, o);
        BitGrid inside = fillInside(frame, mesh, o, &surface);
        combine(inside, surface, o.mode == VoxelizeMode::Interior);
        return {frame, std::move(inside)};
    }
    }
    VOXFX_CHECK(false);
    return {};
}

} // namespace

namespace {

// resolveFill with the mesh's topology given (known) or analyzed here (null).
Fill resolveFillWith(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& o,
                     const MeshTopology* known) {
    VoxelizeReport r;
    r.fill = o.fill;
    if (o.fill == Fill::Auto) {
        r.fill = Fill::Parity;
        if (needsFill(o.mode)) {
            r.topology = known ? *known : analyzeTopology(mesh);
            r.topologyAnalyzed = true;
            if (!r.topology.closed()) {
                const bool gridWalk = !frame.isPerspective() && !frame.isOriented() &&
                                      frame.slicing() == Slicing::Uniform && o.slicing == Slicing::Uniform;
                r.fill = gridWalk ? Fill::Flood : Fill::Gwn;
                r.fillNote = detail::concat(
                    "not closed (", r.topology.boundaryEdges, " boundary, ", r.topology.nonManifoldEdges,
                    " non-manifold, ", r.topology.misorientedEdges, " misoriented edges): ",
                    gridWalk ? "filled by flood (holes wider than a voxel let the flood in; the gwn fill "
                               "closes them)"
                             : "filled by gwn (the generalized winding number; flood needs an axis-aligned, "
                               "uniformly sliced orthographic grid)");
            }
        }
    }
    if (o.report) *o.report = r;
    return r.fill;
}

} // namespace

// Fill::Auto, decided once for every front end: parity is exact for a closed mesh; on an open
// one it fills wrong cells, and flood is robust to holes narrower than a voxel. Flood walks an
// axis-aligned grid (requireUniformOrthographic), so a frame it cannot run in (perspective,
// oriented, locally sliced: light views) takes the generalized winding number instead.
Fill resolveFill(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& o) {
    return resolveFillWith(mesh, frame, o, nullptr);
}

const char* toString(VoxelizeMode m) { return enumName(m, kVoxelizeModeNames); }

bool needsFill(VoxelizeMode mode) {
    return mode == VoxelizeMode::Solid || mode == VoxelizeMode::SolidConservative ||
           mode == VoxelizeMode::Interior;
}

const char* toString(Fill f) { return enumName(f, kFillNames); }

VoxelizeMode parseVoxelizeMode(const std::string& name) {
    return parseEnum<VoxelizeMode>(name, "voxelization mode", kVoxelizeModeNames);
}

Fill parseFill(const std::string& name) { return parseEnum<Fill>(name, "fill", kFillNames); }

Axis parseAxis(const std::string& name) { return parseEnum<Axis>(name, "axis", kAxisNames); }

Slicing parseSlicing(const std::string& name) { return parseEnum<Slicing>(name, "slicing", kSlicingNames); }

Frame fitFrame(const Box3d& meshBounds, const FitOptions& o) {
    const Box3d bounds = o.bounds.empty() ? meshBounds : o.bounds;
    if (bounds.empty()) fail("nothing to voxelize: the mesh has no triangles");
    if (!isFinite(bounds.lo) || !isFinite(bounds.hi)) fail("the bounds are not finite");
    const int given = (o.resolution > 0) + (o.voxelSize > 0) + (o.dims.x > 0 || o.dims.y > 0 || o.dims.z > 0);
    if (given != 1) fail("give exactly one of resolution, voxel size or dims");
    if (o.marginCells < 0) fail("the margin must be >= 0 cells, got ", o.marginCells);
    if (o.cube && o.resolution <= 0) fail("a cube grid needs a resolution");
    const Vec3d ext = bounds.extent();
    Vec3i dims;
    Vec3d cell;
    if (o.dims.x > 0 || o.dims.y > 0 || o.dims.z > 0) {
        for (int a = 0; a < 3; ++a) {
            if (o.dims[a] <= 0)
                fail("dims must all be positive, got ", o.dims.x, " ", o.dims.y, " ", o.dims.z);
            if (!(ext[a] > 0))
                fail("the bounds are flat along ", toString(Axis(a)), "; give --bounds or --voxel-size");
            dims[a] = o.dims[a];
            cell[a] = ext[a] / double(dims[a]);
        }
    } else {
        double size = o.voxelSize;
        if (o.resolution > 0) {
            const double longest = std::max({ext.x, ext.y, ext.z});
            if (!(longest > 0)) fail("the bounds are a single point; give --voxel-size or --bounds");
            size = longest / double(o.resolution);
        }
        if (!(size > 0) || !std::isfinite(size))
            fail("the voxel size must be positive and finite, got ", size);
        for (int a = 0; a < 3; ++a) {
            // Cells along the axis; the longest axis of a resolution fit gets exactly N (the tiny
            // tolerance keeps rounding from adding a cell there).
            const double n = o.cube ? double(o.resolution) : std::ceil(ext[a] / size * (1.0 - 1e-12));
            if (n > 1e9)
                fail("the grid would need ", n, " cells along ", toString(Axis(a)),
                     "; use a larger voxel size");
            dims[a] = std::max<int64_t>(1, int64_t(n));
            cell[a] = size;
        }
    }
    Box3d box;
    for (int a = 0; a < 3; ++a) {
        const double half = 0.5 * double(dims[a]) * cell[a];
        const bool exact = o.dims[a] > 0 || (o.resolution > 0 && double(dims[a]) * cell[a] == ext[a]);
        // Centre the grid on the bounds; keep the bounds exactly where the cells fill them.
        box.lo[a] = exact ? bounds.lo[a] : bounds.center()[a] - half;
        box.hi[a] = exact ? bounds.hi[a] : bounds.center()[a] + half;
        box.lo[a] -= double(o.marginCells) * cell[a];
        box.hi[a] += double(o.marginCells) * cell[a];
        dims[a] += 2 * o.marginCells;
    }
    const int cx = columnXAxis(o.axis), cy = columnYAxis(o.axis), cs = sliceAxis(o.axis);
    std::ostringstream what;
    what << "a " << dims.x << " x " << dims.y << " x " << dims.z << " grid";
    if (o.checkDenseMemory)
        checkMemory(BitGrid::requiredBytes(dims[cx], dims[cy], dims[cs]), what.str().c_str());
    return Frame::orthographic(box, o.axis, dims[cx], dims[cy], dims[cs]);
}

VoxelGrid voxelize(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& options) {
    validateMesh(mesh, "mesh");
    VoxelizeOptions o = options;
    VoxelGrid result;
    withThreads(o.threads, [&] {
        if (options.fill == Fill::Auto && needsFill(options.mode)) {
            // The closed-mesh test of Fill::Auto and the parity fill it picks for closed meshes (the
            // common case) run side by side; an open mesh drops the parity grid and runs its fill.
            VoxelizeOptions parity = options;
            parity.fill = Fill::Parity;
            parity.report = nullptr;
            MeshTopology topology;
            std::exception_ptr failed;
            parallelInvoke([&] { topology = analyzeTopology(mesh); },
                           [&] {
                               try {
                                   result = voxelizePadded(mesh, frame, parity);
                               } catch (...) { failed = std::current_exception(); }
                           });
            o.fill = resolveFillWith(mesh, frame, options, &topology);
            if (failed) std::rethrow_exception(failed);
            if (o.fill == Fill::Parity) return;
            result = {};
        } else {
            o.fill = resolveFill(mesh, frame, options);
        }
        if (frame.isPerspective() && (o.fill == Fill::Flood || o.fill == Fill::Vote) && needsFill(o.mode))
            fail("fill '", toString(o.fill), "' needs an orthographic frame");
        result = voxelizePadded(mesh, frame, o);
    });
    return result;
}

} // namespace voxfx
