// voxfx_vdb — polygons through OpenVDB's volumeToMesh: from a level set, or from a dense field
// made into a sparse band first (denseBand).
#include <algorithm>
#include <memory>
#include <vector>

#include <openvdb/tools/VolumeToMesh.h>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

namespace {

// OpenVDB's polygons as plain arrays.
void copyPolygons(const std::vector<openvdb::Vec3s>& points, const std::vector<openvdb::Vec3I>& triangles,
                  const std::vector<openvdb::Vec4I>& quads, VdbPolygons* out) {
    out->points.resize(3 * points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        for (int a = 0; a < 3; ++a) out->points[3 * i + std::size_t(a)] = points[i][a];
    out->triangles.resize(3 * triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        for (int a = 0; a < 3; ++a) out->triangles[3 * i + std::size_t(a)] = triangles[i][a];
    out->quads.resize(4 * quads.size());
    for (std::size_t i = 0; i < quads.size(); ++i)
        for (int a = 0; a < 4; ++a) out->quads[4 * i + std::size_t(a)] = quads[i][a];
}

void meshFloatGrid(const openvdb::FloatGrid& grid, double isovalue, double adaptivity, VdbPolygons* out) {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    try {
        openvdb::tools::volumeToMesh(grid, points, triangles, quads, isovalue, adaptivity);
    } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
    copyPolygons(points, triangles, quads, out);
}

} // namespace

bool levelSetToMesh(const void* g, double isovalue, double adaptivity, VdbPolygons* out, std::string* error) {
    return guarded(error, [&] { meshFloatGrid(lsGrid(g), isovalue, adaptivity, out); });
}

namespace {

// The dense field as a sparse level set for the mesher: a voxel is active where one of its 26
// neighbours lies on the other side of the iso value (beyond the box: the background, outside), so
// every corner of every cell the surface crosses is an active voxel of a real leaf, with its value;
// leaves without an active voxel hold one side only and become inactive tiles (inside:
// -background) or nothing (outside). volumeToMesh then works on the band, not the whole volume.
// "Some neighbour differs" is the 3 x 3 x 3 maximum of the inside flags differing from their
// minimum, taken one axis at a time (z, y, then x per leaf) over flags padded by one outside cell:
// bit 0 the maximum (some cell inside), bit 1 the minimum (every cell inside). Leaves are made in
// parallel, only where the band passes, and inserted in their order (a deterministic tree).
openvdb::FloatGrid::Ptr denseBand(const float* values, const int64_t dims[3], bool zFastest, float background,
                                  double isovalue, ParallelFor parallelFor) {
    const int64_t nx = dims[0], ny = dims[1], nz = dims[2];
    const int64_t py = ny + 2, pz = nz + 2;
    const auto at = [&](int64_t i, int64_t j, int64_t k) {
        return zFastest ? values[(i * ny + j) * nz + k] : values[i + nx * (j + ny * k)];
    };
    // Padded index of (i, j, k), z fastest; i, j, k from -1 to n.
    const auto pad = [&](int64_t i, int64_t j, int64_t k) {
        return std::size_t(((i + 1) * py + (j + 1)) * pz + k + 1);
    };
    const std::size_t padded = std::size_t((nx + 2) * py * pz);
    // inside: the flags, then (passY) their min/max over j and k; alongZ: over k. Zero (outside,
    // neither bit) in the padding.
    std::vector<uint8_t> inside(padded, 0), alongZ(padded, 0);
    std::vector<uint8_t>& span = inside;
    auto flags = [&](int64_t b, int64_t e) {
        // Locals, so that the byte stores (which may alias anything) do not reload them.
        const float* v = values;
        const double iso = isovalue;
        const int64_t strideK = zFastest ? 1 : nx * ny;
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                uint8_t* row = &inside[pad(i, j, 0)];
                const float* src = zFastest ? v + (i * ny + j) * nz : v + i + nx * j;
                for (int64_t k = 0; k < nz; ++k) row[k] = double(src[k * strideK]) < iso;
            }
    };
    forChunks(parallelFor, 0, nx, 4, flags);
    auto passZ = [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                const uint8_t* f = &inside[pad(i, j, 0)];
                uint8_t* out = &alongZ[pad(i, j, 0)];
                for (int64_t k = 0; k < nz; ++k)
                    out[k] = uint8_t((f[k - 1] | f[k] | f[k + 1]) | ((f[k - 1] & f[k] & f[k + 1]) << 1));
            }
    };
    forChunks(parallelFor, 0, nx, 4, passZ);
    auto passY = [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                const uint8_t* lo = &alongZ[pad(i, j - 1, 0)];
                const uint8_t* mid = &alongZ[pad(i, j, 0)];
                const uint8_t* hi = &alongZ[pad(i, j + 1, 0)];
                uint8_t* out = &span[pad(i, j, 0)];
                for (int64_t k = 0; k < nz; ++k)
                    out[k] = uint8_t(((lo[k] | mid[k] | hi[k]) & 1) | (lo[k] & mid[k] & hi[k] & 2));
            }
    };
    forChunks(parallelFor, 0, nx, 4, passY);
    const int64_t lx = (nx + 7) / 8, ly = (ny + 7) / 8, lz = (nz + 7) / 8;
    std::vector<std::unique_ptr<FloatLeaf>> leaves(std::size_t(lx * ly * lz));
    std::vector<uint8_t> insideTile(leaves.size(), 0);
    auto body = [&](int64_t b, int64_t e) {
        const std::size_t d = std::size_t(py * pz);
        for (int64_t l = b; l < e; ++l) {
            // Leaves in z-fastest order, as the padded flags lie in memory.
            const int64_t i0 = 8 * (l / (ly * lz)), j0 = 8 * (l / lz % ly), k0 = 8 * (l % lz);
            const int64_t i1 = std::min(i0 + 8, nx), j1 = std::min(j0 + 8, ny), k1 = std::min(k0 + 8, nz);
            // The leaf's active mask (along x: the last pass). OpenVDB's voxel (di, dj, dk) is bit
            // (dj << 3) | dk of mask word di: one byte per row of 8 along z.
            uint64_t words[8] = {0, 0, 0, 0, 0, 0, 0, 0};
            for (int64_t i = i0; i < i1; ++i)
                for (int64_t j = j0; j < j1; ++j) {
                    const uint8_t* lo = &span[pad(i, j, k0)] - d;
                    const uint8_t* mid = lo + d;
                    const uint8_t* hi = mid + d;
                    uint64_t row = 0;
                    for (int64_t k = 0; k < k1 - k0; ++k) {
                        const unsigned some = (lo[k] | mid[k] | hi[k]) & 1u,
                                       all = (lo[k] & mid[k] & hi[k]) >> 1;
                        row |= uint64_t(some & ~all & 1u) << k;
                    }
                    words[i - i0] |= row << (8 * (j - j0));
                }
            if (!(words[0] | words[1] | words[2] | words[3] | words[4] | words[5] | words[6] | words[7])) {
                // One side only (see above): inside when its first voxel's whole neighbourhood is.
                insideTile[std::size_t(l)] = (span[pad(i0, j0, k0)] >> 1) & 1;
                continue;
            }
            FloatLeaf::NodeMaskType mask;
            for (int w = 0; w < 8; ++w) mask.template getWord<uint64_t>(openvdb::Index(w)) = words[w];
            auto leaf =
                std::make_unique<FloatLeaf>(openvdb::Coord(int(i0), int(j0), int(k0)), background, false);
            float* buffer = leaf->buffer().data();
            for (int64_t i = i0; i < i1; ++i)
                for (int64_t j = j0; j < j1; ++j)
                    for (int64_t k = k0; k < k1; ++k)
                        buffer[((i - i0) << 6) | ((j - j0) << 3) | (k - k0)] = at(i, j, k);
            leaf->setValueMask(mask);
            leaves[std::size_t(l)] = std::move(leaf);
        }
    };
    forChunks(parallelFor, 0, int64_t(leaves.size()), 16, body);
    auto grid = openvdb::FloatGrid::create(background);
    auto& tree = grid->tree();
    for (std::size_t l = 0; l < leaves.size(); ++l) {
        if (leaves[l]) {
            tree.addLeaf(leaves[l].release());
        } else if (insideTile[l]) {
            const auto L = int64_t(l);
            tree.addTile(1,
                         openvdb::Coord(int(8 * (L / (ly * lz))), int(8 * (L / lz % ly)), int(8 * (L % lz))),
                         -background, false);
        }
    }
    return grid;
}

} // namespace

bool denseToMesh(const float* values, const int64_t dims[3], bool zFastest, const VdbPlacement& placement,
                 float background, double isovalue, double adaptivity, ParallelFor parallelFor,
                 VdbPolygons* out, std::string* error) {
    return guarded(error, [&] {
        initializeOpenVdb();
        auto grid = denseBand(values, dims, zFastest, background, isovalue, parallelFor);
        auto xform = openvdb::math::Transform::createLinearTransform(1.0);
        xform->preScale(openvdb::Vec3d(placement.cell[0], placement.cell[1], placement.cell[2]));
        xform->postTranslate(
            openvdb::Vec3d(placement.centre0[0], placement.centre0[1], placement.centre0[2]));
        grid->setTransform(xform);
        // volumeToMesh reads a level set's inside as below the iso value (other float grids as fog
        // volumes: above it), which is this function's convention.
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        meshFloatGrid(*grid, isovalue, adaptivity, out);
    });
}

} // namespace voxfx::detail::vdbmodule
