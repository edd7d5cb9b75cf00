// voxfx sdf MESH -o FIELD — the signed distance field of a mesh: an OpenVDB level set or dense
// floats (voxfx/sdf.hpp, voxfx/sdf_io.hpp).
#include <algorithm>
#include <cmath>
#include <iostream>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/level_set.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/sdf_io.hpp"

namespace voxfx::cli {
namespace {

struct SdfArgs {
    std::string input, output;
    FitArgs fit;
    std::string band = "3";
    std::string fill = "auto";
    double offset = 0;
    int threads = 0;
    bool quiet = false;
};

const FitChoices& sdfFitChoices() {
    static const FitChoices choices = [] {
        FitChoices c;
        c.voxelSize = c.bounds = true;
        c.defaultMargin = -1;
        c.marginHelp = "Cells added on every side (default: the band width rounded up, so the band "
                       "outside the mesh is not cut; 0 with --band full)";
        return c;
    }();
    return choices;
}

// "full", or a number of voxels >= 1.
SdfOptions parseBand(const std::string& band) {
    SdfOptions o;
    if (band == "full") {
        o.full = true;
        return o;
    }
    std::size_t used = 0;
    double w = 0;
    try {
        w = std::stod(band, &used);
    } catch (const std::exception&) { used = 0; }
    if (used != band.size() || !(w >= 1) || !std::isfinite(w))
        fail("--band: expected a width in voxels (at least 1) or 'full', got '", band, "'");
    o.bandVoxels = w;
    return o;
}

int runSdf(const SdfArgs& a) {
    const auto t0 = Clock::now();
    // Everything that can be checked before the work is checked first.
    const SdfFormat format = sdfFormatFromPath(a.output);
    SdfOptions so = parseBand(a.band);
    so.threads = a.threads;
    so.fill = parseFill(a.fill);
    if (!std::isfinite(a.offset)) fail("--offset: expected a finite distance, got ", a.offset);
    const int64_t margin =
        a.fit.margin >= 0 ? a.fit.margin : (so.full ? 0 : int64_t(std::ceil(so.bandVoxels)));
    FitOptions fo = toFitOptions(a.fit, sdfFitChoices(), margin);

    prepareGridFormat(a.output, /*background=*/true); // a .vdb's module loads beside the mesh load
    const Mesh mesh = loadMesh(a.input);
    const double loadMs = msSince(t0);
    const auto tm = Clock::now();
    prepareGridFormat(a.output); // what is left of it, counted in the write
    const double moduleMs = msSince(tm);
    Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    if (a.offset > 0 && a.fit.margin < 0) {
        // Room for the grown surface and its band: the cell size does not depend on the margin.
        const Vec3d c = frame.cellSize();
        fo.marginCells = margin + int64_t(std::ceil(a.offset / std::max({c.x, c.y, c.z})));
        frame = fitFrame(computeBounds(mesh.view()), fo);
    }
    ProgressLine progress("distances", !a.quiet);
    so.progress = &progress;
    const auto ts = Clock::now();
    SdfWriteReport made;
    if (a.offset != 0) {
        // The offset surface's field is made whole (exact distances to the moved surface), then
        // written.
        made.field = offsetSignedDistanceField(mesh.view(), frame, a.offset, so);
        made.activeCount = made.field.activeCount();
        const auto tw = Clock::now();
        writeSdf(made.field, a.output);
        made.writeSeconds = msSince(tw) / 1000;
    } else {
        // Computed and written in one call: a .vdb takes the field brick by brick into its tree.
        made = writeSdf(mesh.view(), frame, so, a.output);
    }
    const SignedDistanceField& field = made.field; // its description; the values are in the file
    const double sdfMs = msSince(ts) - made.writeSeconds * 1000,
                 writeMs = made.writeSeconds * 1000 + moduleMs;
    progress.done();

    if (!a.quiet) {
        const Vec3i d = field.dims();
        const Vec3d cell = field.frame.cellSize();
        const Vec3d c0 = field.frame.box().lo + cell * 0.5;
        std::cout << a.input << ": " << withCommas(int64_t(mesh.triangleCount())) << " triangles -> " << d.x
                  << " x " << d.y << " x " << d.z << " grid (cell " << fmt(cell.x, 4)
                  << ", voxel (0, 0, 0) centred at (" << fmt(c0.x, 6) << ", " << fmt(c0.y, 6) << ", "
                  << fmt(c0.z, 6) << ")), ";
        if (field.full)
            std::cout << "every voxel";
        else
            std::cout << "band " << fmt(field.bandVoxels, 4) << " voxels (" << fmt(field.background, 4)
                      << ")";
        if (a.offset != 0)
            std::cout << ", offset by " << fmt(a.offset, 6) << (a.offset > 0 ? " (grown)" : " (shrunk)");
        std::cout << ", sign from " << toString(field.fill) << ": " << withCommas(made.activeCount)
                  << " active voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", distances " << fmtMs(sdfMs) << ", write "
                  << fmtMs(writeMs) << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << " ("
                  << (format == SdfFormat::Vdb ? "vdb level set" : toString(format)) << ")\n";
    }
    return 0;
}

const char* kSdfHelp = R"(
What the values are:
  The value of voxel (i, j, k) is the Euclidean distance from its CENTRE, lo + (i + 0.5) * cell
  (the grid placement of `voxfx voxelize --help`), to the nearest triangle of the mesh; negative
  inside. "Exact": the mesh is its float coordinates, the distance is computed in double
  precision to the nearest triangle (a bounding-volume hierarchy finds it; nothing is
  propagated from voxel to voxel) and rounded once to float: within one float ulp of the true
  value. The sign is the occupancy of `voxfx voxelize -m solid` with the same grid and fill: a
  voxel is negative exactly when that command fills it (-0 for a centre on the surface that
  the tie rule puts inside).

Units and sign:
  Values are lengths in the mesh's own units (those of its coordinates), not voxels: divide by
  the cell edge (the summary's "cell") for voxels. Negative inside, positive outside, zero on the
  surface: OpenVDB's level-set convention, so the 0 isosurface is the mesh (e.g. ParaView's
  Contour at 0 on the .nrrd).

The band (--band W, default 3 voxels, as OpenVDB's level sets):
  Voxels closer than W voxels to the surface are active and hold their exact distance; every
  other voxel holds +W or -W (in world units: the .vdb background). Only voxels near the
  surface are computed (the conservative surface dilated by the band), so the time grows with
  the surface, not with the grid. --band full computes every voxel exactly, however far (each
  block of 8^3 voxels gathers the triangles that can be nearest to it): the time grows with the
  grid; its background is the grid's diagonal. --margin defaults to the band rounded up (0 with
  full), so the band outside the mesh's bounds is not cut off.

The sign (--fill, default auto):
  auto is parity (the exact crossing count) for closed meshes and gwn (generalized winding
  number >= 1/2) for meshes with holes, boundary or non-manifold edges; --fill picks another:
  parity, gwn, winding, flood, vote (see `voxfx voxelize --help`). Parity, winding and gwn are
  decided brick by brick, so memory grows with the surface; flood and vote need the whole grid's
  solid in memory (one bit per voxel).

Offset (--offset D, world units):
  The field of the solid grown by D (D > 0) or shrunk by -D (D < 0): the distances are computed
  with the band widened by |D| and D is subtracted, so the band stays W voxels around the new
  surface, and --margin's default grows by D / cell. The zero level is exactly the offset
  surface and the sign that of the offset solid; |value| is the exact distance to the new
  surface on the side away from the mesh (outside when growing, inside when shrinking) and a
  lower bound on the other side (equal wherever the offset surface is smooth; smaller near the
  creases that growing makes in concave parts and shrinking at convex edges). To offset an
  existing level-set .vdb (OpenVDB's LevelSetFilter, approximate): voxfx morph IN.vdb --offset D.

Formats (by extension; written atomically):
  .vdb   OpenVDB FloatGrid "sdf", class level set, background = band width: sparse, opens in
         Houdini, Blender and openvdb.read(); index (i, j, k) maps to the voxel's centre.
  .nrrd  dense float32 with the placement (space origin = centre of voxel 0,0,0)
  .npy   dense float32, shape (nx, ny, nz), indexed [i, j, k]: numpy.load(); the placement is
         the summary line's "voxel (0, 0, 0) centred at" and cell.
  Dense files hold every voxel (4 bytes each): for grids that fit in memory.
  Nothing is written on an error; a progress line shows on a terminal for runs over 0.3 s.)";

const Command kSdf{
    "sdf", "Signed distance field of a mesh (.vdb level set, .nrrd, .npy)", [](CLI::App& app) {
        app.footer(kSdfHelp);
        auto a = std::make_shared<SdfArgs>();
        app.add_option("MESH", a->input, "Mesh file (off, obj, ply, stl, gltf, glb, ...)")->required();
        app.add_option("-o,--output", a->output, "Output: .vdb (level set), .nrrd or .npy (dense)")
            ->required();
        addFitOptions(app, a->fit, sdfFitChoices());
        app.add_option("--band", a->band,
                       "Half-width of the narrow band in voxels (>= 1), or 'full' (default 3)");
        app.add_option("--fill", a->fill,
                       "Inside test behind the sign: auto (parity if closed, else gwn), parity, "
                       "gwn, winding, flood, vote");
        app.add_option("--offset", a->offset,
                       "Grow (> 0) or shrink (< 0) the solid by this distance, world units (default 0)");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->default_val(0)
            ->check(CLI::NonNegativeNumber);
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        return std::function<int()>([a] { return runSdf(*a); });
    }};

} // namespace
} // namespace voxfx::cli
