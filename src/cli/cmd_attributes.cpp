// voxfx attributes MESH -o FILE — CHANG's attribute voxelization written out (voxfx/attribute_grid.hpp,
// voxfx/attribute_io.hpp): per voxel the writes, the average normal, the material, its refraction
// index and attenuation, so the grid the voxel glass methods march can be looked at in ParaView.
#include <cmath>
#include <iostream>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/attribute_io.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/scene_io.hpp"

namespace voxfx::cli {
namespace {

struct AttributesArgs {
    std::string input, output;
    FitArgs fit;
    std::string channels;
    std::string coverage = "center";
    double slabOverlap = 0;
    int threads = 0;
    bool quiet = false;
};

const FitChoices& attributesFitChoices() {
    static const FitChoices choices = [] {
        FitChoices c;
        c.defaultResolution = 128;
        c.defaultMargin = 1;
        c.voxelSize = c.dims = c.bounds = true;
        return c;
    }();
    return choices;
}

// Every mesh of the scene as one mesh, with the scene mesh's material per triangle.
struct Merged {
    Mesh mesh;
    std::vector<uint32_t> triangleMaterial;
    std::vector<AttributeMaterial> materials;
};

Merged merge(const Scene& scene) {
    Merged m;
    for (const SceneMesh& s : scene.meshes) {
        const auto base = uint32_t(m.mesh.positions.size());
        m.mesh.positions.insert(m.mesh.positions.end(), s.mesh.positions.begin(), s.mesh.positions.end());
        for (const uint32_t i : s.mesh.indices) m.mesh.indices.push_back(base + i);
        m.triangleMaterial.insert(m.triangleMaterial.end(), s.mesh.indices.size() / 3, s.material);
    }
    for (const Material& mat : scene.materials) m.materials.push_back({mat.ior, attenuationCoefficient(mat)});
    return m;
}

int runAttributes(const AttributesArgs& a) {
    const auto t0 = Clock::now();
    // Everything that can be checked before the work is checked first.
    const std::string ext = fileExtension(a.output);
    const bool vdb = ext == ".vdb";
    if (!vdb && ext != ".nrrd" && ext != ".npy")
        fail("'", a.output, "': unknown attribute grid extension '", ext, "' (allowed: .vdb .nrrd .npy)");
    AttributeOptions ao;
    ao.channels = parseAttributeChannels(a.channels.empty() ? (vdb ? "count,normal,material,ior" : "normal")
                                                            : a.channels);
    if (ao.channels.absorption)
        fail("--channels: absorption needs per-triangle values (the absorption shadows' input); "
             "choose from count, normal, material, ior, attenuation");
    const std::vector<AttributeChannel> list = channelList(ao.channels);
    if (!vdb && list.size() > 1)
        fail("--channels: a ", ext, " file holds one channel, got ", list.size(),
             " (write .vdb for several)");
    ao.coverage = parseCoverage(a.coverage);
    if (ao.coverage != Coverage::Center && ao.coverage != Coverage::Conservative)
        fail("--coverage: expected center or conservative, got '", a.coverage, "'");
    if (!(a.slabOverlap >= 0) || !std::isfinite(a.slabOverlap))
        fail("--slab-overlap: expected a finite number of slices >= 0, got ", a.slabOverlap);
    ao.slabOverlap = a.slabOverlap;
    ao.threads = a.threads;
    const FitOptions fo = toFitOptions(a.fit, attributesFitChoices());

    const Scene scene = loadScene(a.input);
    const Merged m = merge(scene);
    ao.triangleMaterial = m.triangleMaterial;
    ao.materials = m.materials;
    const double loadMs = msSince(t0);
    const Frame frame = fitFrame(computeBounds(m.mesh.view()), fo);
    ProgressLine progress("attributes", !a.quiet);
    ao.progress = &progress;
    const auto tv = Clock::now();
    const AttributeGrid grid = voxelizeAttributes(m.mesh.view(), frame, {}, ao);
    const double voxelizeMs = msSince(tv);
    progress.done();
    const auto tw = Clock::now();
    writeAttributeGrid(grid, a.output);
    const double writeMs = msSince(tw);

    if (!a.quiet) {
        int64_t written = 0;
        for (int64_t i = 0; i < grid.voxelCount(); ++i) written += grid.written(i);
        std::cout << a.input << ": " << withCommas(int64_t(m.mesh.triangleCount())) << " triangles, "
                  << m.materials.size() << (m.materials.size() == 1 ? " material" : " materials") << " -> "
                  << frame.width() << " x " << frame.height() << " x " << frame.depth() << " grid (cell "
                  << fmt(frame.cellSize().x, 4) << "), ";
        if (grid.count.empty() && grid.material.empty() && grid.ior.empty())
            std::cout << "channels";
        else
            std::cout << withCommas(written) << " voxels written, channels";
        for (std::size_t k = 0; k < list.size(); ++k) std::cout << (k ? ", " : " ") << toString(list[k]);
        std::cout << "\ntime: load " << fmtMs(loadMs) << ", voxelize " << fmtMs(voxelizeMs) << ", write "
                  << fmtMs(writeMs) << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << "\n";
    }
    return 0;
}

const char* kAttributesHelp = R"(
What is written (CHANG's attribute voxelization, the grid `render --glass multi` marches):
  Every triangle writes the voxels it covers: with --coverage center (CHANG, the default) the
  voxel of each column centre it covers, in the slice of its depth there (with --slab-overlap W
  also the slices whose slabs, widened by W slices on each side, hold that depth: steep
  triangles then leave fewer holes); with conservative every voxel its surface touches.
  Channels (--channels, a comma list):
    count        writes per voxel
    normal       the unit average of the writes' triangle normals (outward for closed meshes)
    material     the material index of the voxel's first write (lowest triangle index)
    ior          that material's refraction index (glTF KHR_materials_ior; 1.5 by default)
    attenuation  that material's Beer-Lambert coefficient per unit length, RGB (glTF
                 KHR_materials_volume: -ln(attenuationColor) / attenuationDistance)
  Materials come from the scene (.gltf, .glb, a scene .json); any other mesh is one material.

Formats (by extension; written atomically, nothing on an error):
  .vdb   every channel asked for (default count, normal, material, ior) as OpenVDB grids of
         those names: FloatGrid, Vec3SGrid for normal and attenuation; written voxels active;
         index (i, j, k) maps to the voxel's centre. ParaView, Houdini, Blender open it.
  .nrrd  one channel (default normal): ushort count, uint material, float otherwise; vectors
         as a 3-vector axis first; "space origin" is the centre of voxel (0, 0, 0).
  .npy   one channel as .nrrd, shape (nx, ny, nz) or (3, nx, ny, nz): numpy.load().

Example:
  voxfx attributes glass.glb -o glass.vdb -r 256
  voxfx attributes bunny.off -o normals.nrrd --channels normal --coverage conservative)";

const Command kAttributes{
    "attributes", "Per-voxel normals, materials, refraction indices of a mesh (.vdb, .nrrd, .npy)",
    [](CLI::App& app) {
        app.footer(kAttributesHelp);
        auto a = std::make_shared<AttributesArgs>();
        app.add_option("MESH", a->input,
                       "Mesh or scene file (off, obj, ply, stl, gltf, glb, scene json, ...)")
            ->required();
        app.add_option("-o,--output", a->output, "Output: .vdb (all channels), .nrrd or .npy (one channel)")
            ->required();
        addFitOptions(app, a->fit, attributesFitChoices());
        app.add_option(
            "--channels", a->channels,
            "Channels: count, normal, material, ior, attenuation (default: count,normal,material,ior "
            "for .vdb, normal otherwise)");
        app.add_option("--coverage", a->coverage,
                       "center (CHANG: one write per covered column centre) or "
                       "conservative (every voxel the surface touches)")
            ->default_val("center");
        app.add_option("--slab-overlap", a->slabOverlap,
                       "CHANG's widened slabs: slices added on each side of a slab (>= 0)")
            ->default_val(0);
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->default_val(0)
            ->check(CLI::NonNegativeNumber);
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        return std::function<int()>([a] { return runAttributes(*a); });
    }};

} // namespace
} // namespace voxfx::cli
