// CHANG §2 widened slabs: missed against doubled voxels of centre-coverage attribute voxelization as
// AttributeOptions::slabOverlap grows, against the cells the surface passes through (conservative
// coverage, which the tests check against CGAL's exact triangle/box overlap). Prints a table.
//
//   ./build/bench_attribute_overlap [mesh.off] [resolution]   (default: the Chinese dragon, 256)
#include <cstdio>
#include <cstdlib>
#include <string>

#include "voxfx/voxfx.hpp"

int main(int argc, char** argv) {
    using namespace voxfx;
    const std::string path =
        argc > 1 ? argv[1] : std::string(VOXFX_DATA_DIR) + "/meshes/ChineseDragon-10kv.off";
    const Mesh m = loadMesh(path);
    FitOptions fo;
    fo.resolution = argc > 2 ? std::atoi(argv[2]) : 256;
    const Frame f = fitFrame(computeBounds(m.view()), fo);
    AttributeOptions o;
    o.channels = AttributeChannels::shadows();
    o.coverage = Coverage::Conservative;
    const BitGrid surface = voxelizeAttributes(m.view(), f, {}, o).occupancy();
    std::printf("%s, %lldx%lldx%lld, %lld surface cells\n", path.c_str(), (long long)f.width(),
                (long long)f.height(), (long long)f.depth(), (long long)surface.count());
    std::printf("| overlap w (slices) | written | missed | doubled |\n|---:|---:|---:|---:|\n");
    o.coverage = Coverage::Center;
    for (const double w : {0.0, 0.25, 0.5, 1.0, 2.0}) {
        o.slabOverlap = w;
        const BitGrid got = voxelizeAttributes(m.view(), f, {}, o).occupancy();
        long long missed = 0, doubled = 0;
        for (int64_t y = 0; y < f.height(); ++y)
            for (int64_t x = 0; x < f.width(); ++x)
                for (int64_t s = 0; s < f.depth(); ++s) {
                    const bool want = surface.get(x, y, s), have = got.get(x, y, s);
                    missed += want && !have;
                    doubled += have && !want;
                }
        const double n = double(surface.count());
        std::printf("| %g | %lld | %lld (%.1f %%) | %lld (%.1f %%) |\n", w, (long long)got.count(), missed,
                    100.0 * double(missed) / n, doubled, 100.0 * double(doubled) / n);
    }
    return 0;
}
