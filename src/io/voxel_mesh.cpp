// voxfx — the exposed faces of filled voxels as a quad mesh (.ply binary little endian, .obj).
//
// A face is exposed when it separates a filled voxel from an empty one or from the outside of
// the grid. Faces come from whole words: with the grid sliced along axis a, a column's bits run
// along a and
//     minus faces (towards -a) = v & ~(v << 1)      plus faces (towards +a) = v & ~(v >> 1)
// (with the neighbouring word's edge bit carried in; padding bits are zero, so the grid border
// counts as empty). Quads wind counter-clockwise seen from outside (normals point out of the
// solid).
//
// Vertices are shared: each lattice point used by an exposed face is emitted once. A lattice
// point is used exactly when the 2 x 2 x 2 voxels around it are not all equal (two of them then
// differ across a face through the point, the block being connected), so the vertex set comes
// from the z-sliced grid with a few word operations per lattice column, and a vertex's index is
// a rank: per-column prefix + per-word prefix + popcount below the bit. Counts first, then every
// part is formatted in parallel chunks and written in order (deterministic output).
#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/grid_formats.hpp"
#include "io/ply_header.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

namespace {

// Lattice points (i, j, k), 0 <= i <= nx etc., that are vertices of exposed faces.
class VertexSet {
public:
    explicit VertexSet(const VoxelGrid& gz) {
        const BitGrid& bits = gz.bits; // columns (x, y), bits along z
        nx_ = bits.width();
        ny_ = bits.height();
        nz_ = bits.depth();
        lx_ = nx_ + 1;
        const int64_t ly = ny_ + 1, lz = nz_ + 1, wpc = bits.wordsPerColumn();
        lwpc_ = (lz + 63) / 64;
        const int64_t columns = lx_ * ly;
        mixed_.assign(size_t(columns * lwpc_), 0);
        wordRank_.assign(size_t(columns * lwpc_), 0);
        columnStart_.assign(size_t(columns + 1), 0);
        parallelFor(0, columns, 1024, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const int64_t i = c % lx_, j = c / lx_;
                // The four voxel columns around lattice column (i, j); outside ones are empty.
                const uint64_t* around[4];
                int n = 0;
                bool all = true;
                for (int64_t y = j - 1; y <= j; ++y)
                    for (int64_t x = i - 1; x <= i; ++x) {
                        if (x >= 0 && x < nx_ && y >= 0 && y < ny_)
                            around[n++] = bits.column(x, y);
                        else
                            all = false;
                    }
                uint64_t carryOr = 0, carryAnd = 0;
                uint32_t count = 0;
                for (int64_t w = 0; w < lwpc_; ++w) {
                    uint64_t anyOn = 0, allOn = all ? ~uint64_t(0) : 0;
                    for (int t = 0; t < n; ++t) {
                        const uint64_t word = w < wpc ? around[t][w] : 0;
                        anyOn |= word;
                        allOn &= word;
                    }
                    // Lattice point k touches voxel slices k-1 and k:
                    //   bit k of (x << 1 | carry) is voxel k-1's bit.
                    const uint64_t anyOn2 = anyOn | (anyOn << 1) | carryOr;
                    const uint64_t allOn2 = allOn & ((allOn << 1) | carryAnd);
                    carryOr = anyOn >> 63;
                    carryAnd = allOn >> 63;
                    uint64_t m = anyOn2 & ~allOn2;
                    if (w == lwpc_ - 1 && (lz & 63)) m &= (uint64_t(1) << (lz & 63)) - 1;
                    mixed_[size_t(c * lwpc_ + w)] = m;
                    wordRank_[size_t(c * lwpc_ + w)] = count;
                    count += uint32_t(std::popcount(m));
                }
                columnStart_[size_t(c + 1)] = count;
            }
        });
        for (int64_t c = 0; c < columns; ++c) columnStart_[size_t(c + 1)] += columnStart_[size_t(c)];
    }

    int64_t count() const { return columnStart_.back(); }
    int64_t latticeColumns() const { return lx_ * (ny_ + 1); }
    int64_t columnStart(int64_t c) const { return columnStart_[size_t(c)]; }

    /// Index of lattice point (i, j, k), which must be a vertex.
    int64_t index(int64_t i, int64_t j, int64_t k) const {
        const size_t w = size_t((j * lx_ + i) * lwpc_ + (k >> 6));
        return columnStart_[size_t(j * lx_ + i)] + wordRank_[w] +
               std::popcount(mixed_[w] & ((uint64_t(1) << (k & 63)) - 1));
    }

    /// Calls f(i, j, k) for the vertices of lattice column c in index order.
    template <class F> void forEachInColumn(int64_t c, F&& f) const {
        const int64_t i = c % lx_, j = c / lx_;
        for (int64_t w = 0; w < lwpc_; ++w)
            for (uint64_t m = mixed_[size_t(c * lwpc_ + w)]; m; m &= m - 1)
                f(i, j, w * 64 + std::countr_zero(m));
    }

private:
    int64_t nx_ = 0, ny_ = 0, nz_ = 0, lx_ = 0, lwpc_ = 0;
    std::vector<uint64_t> mixed_;
    std::vector<uint32_t> wordRank_;
    std::vector<int64_t> columnStart_;
};

// Exposed faces of a grid sliced along one axis, counted per column.
struct FaceSet {
    const VoxelGrid& grid; // sliced along the face normal's axis; not owned
    std::vector<int64_t> columnStart;

    explicit FaceSet(const VoxelGrid& g) : grid(g) {
        const int64_t columns = grid.bits.columnCount(), wpc = grid.bits.wordsPerColumn();
        columnStart.assign(size_t(columns + 1), 0);
        parallelFor(0, columns, 1024, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const uint64_t* col = grid.bits.column(c);
                int64_t n = 0;
                for (int64_t w = 0; w < wpc; ++w) {
                    uint64_t minus, plus;
                    faces(col, w, wpc, minus, plus);
                    n += std::popcount(minus) + std::popcount(plus);
                }
                columnStart[size_t(c + 1)] = n;
            }
        });
        for (int64_t c = 0; c < columns; ++c) columnStart[size_t(c + 1)] += columnStart[size_t(c)];
    }

    static void faces(const uint64_t* col, int64_t w, int64_t wpc, uint64_t& minus, uint64_t& plus) {
        const uint64_t v = col[w];
        const uint64_t below = w > 0 ? col[w - 1] >> 63 : 0;       // slice 64w - 1
        const uint64_t above = w + 1 < wpc ? col[w + 1] << 63 : 0; // slice 64w + 64 -> bit 63
        minus = v & ~((v << 1) | below);
        plus = v & ~((v >> 1) | above);
    }

    int64_t count() const { return columnStart.back(); }

    /// Calls f(l0, l1, l2, l3) with the world lattice points (i, j, k) of each face of column c,
    /// counter-clockwise seen from outside.
    template <class F> void forEachInColumn(int64_t c, F&& f) const {
        const Axis a = grid.frame.axis();
        const int ia = sliceAxis(a), iu = columnXAxis(a), iv = columnYAxis(a);
        const int64_t u = c % grid.bits.width(), v = c / grid.bits.width(), wpc = grid.bits.wordsPerColumn();
        const uint64_t* col = grid.bits.column(c);
        auto point = [&](int64_t s, int64_t pu, int64_t pv) {
            Vec3i p;
            p[ia] = s;
            p[iu] = pu;
            p[iv] = pv;
            return p;
        };
        for (int64_t w = 0; w < wpc; ++w) {
            uint64_t minus, plus;
            faces(col, w, wpc, minus, plus);
            // (u, v, a) is right-handed: going +u then +v turns counter-clockwise about +a.
            for (; minus; minus &= minus - 1) {
                const int64_t s = w * 64 + std::countr_zero(minus);
                f(point(s, u, v), point(s, u, v + 1), point(s, u + 1, v + 1), point(s, u + 1, v));
            }
            for (; plus; plus &= plus - 1) {
                const int64_t s = w * 64 + std::countr_zero(plus) + 1;
                f(point(s, u, v), point(s, u + 1, v), point(s, u + 1, v + 1), point(s, u, v + 1));
            }
        }
    }
};

// Formats [0, n) in chunks of `grain` items, in parallel batches, writing chunks in order.
template <class Format> void writeChunked(std::ostream& out, int64_t n, int64_t grain, const Format& format) {
    const int64_t chunks = (n + grain - 1) / grain;
    const int64_t batch = std::max<int64_t>(4, 4 * int64_t(hardwareThreads()));
    std::vector<std::string> bufs(size_t(std::min(batch, std::max<int64_t>(chunks, 1))));
    for (int64_t k0 = 0; k0 < chunks; k0 += batch) {
        const int64_t k1 = std::min(chunks, k0 + batch);
        parallelFor(k0, k1, 1, [&](int64_t b, int64_t e) {
            for (int64_t k = b; k < e; ++k) {
                std::string& s = bufs[size_t(k - k0)];
                s.clear();
                format(k * grain, std::min(n, (k + 1) * grain), s);
            }
        });
        for (int64_t k = k0; k < k1; ++k)
            out.write(bufs[size_t(k - k0)].data(), std::streamsize(bufs[size_t(k - k0)].size()));
    }
}

void appendFloat(std::string& s, float v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    s.append(buf, r.ptr);
}

void appendInt(std::string& s, int64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    s.append(buf, r.ptr);
}

} // namespace

void writeVoxelMesh(const VoxelGrid& grid, std::ostream& out, GridFormat format) {
    VOXFX_CHECK(format == GridFormat::Ply || format == GridFormat::Obj);
    const bool ply = format == GridFormat::Ply;
    const Vec3d lo = grid.frame.box().lo, cell = grid.frame.cellSize();
    // The grid along all three axes, one transpose pass each from the axis it comes in.
    const Axis a0 = grid.frame.axis(), a1 = Axis((int(a0) + 1) % 3), a2 = Axis((int(a0) + 2) % 3);
    const VoxelGrid next = reslice(grid, a1), nextNext = reslice(next, a2);
    const VoxelGrid* sliced[3];
    sliced[int(a0)] = &grid;
    sliced[int(a1)] = &next;
    sliced[int(a2)] = &nextNext;
    const VertexSet vertices(*sliced[int(Axis::Z)]);
    const FaceSet faceSets[3] = {FaceSet(*sliced[0]), FaceSet(*sliced[1]), FaceSet(*sliced[2])};
    const int64_t vertexCount = vertices.count();
    int64_t faceCount = 0;
    for (const FaceSet& f : faceSets) faceCount += f.count();
    if (vertexCount > std::numeric_limits<int32_t>::max())
        fail("the voxel mesh has ", vertexCount, " vertices, more than 32-bit indices can address");

    // World position of lattice point (i, j, k); computed the same way for every face sharing it.
    auto position = [&](int64_t i, int64_t j, int64_t k) {
        return Vec3f(float(lo.x + double(i) * cell.x), float(lo.y + double(j) * cell.y),
                     float(lo.z + double(k) * cell.z));
    };
    auto index = [&](const Vec3i& p) { return vertices.index(p.x, p.y, p.z); };

    if (ply) {
        writePlyHeader(out, "voxfx voxel mesh: exposed faces of filled voxels, world coordinates",
                       {{"vertex", vertexCount, {"float x", "float y", "float z"}},
                        {"face", faceCount, {"list uchar int vertex_indices"}}});
    } else {
        out << "# voxfx voxel mesh: exposed faces of filled voxels, world coordinates\n"
            << "# " << vertexCount << " vertices, " << faceCount << " quads\n";
    }

    constexpr int64_t kGrain = 512;
    writeChunked(out, vertices.latticeColumns(), kGrain, [&](int64_t b, int64_t e, std::string& s) {
        if (ply) {
            s.resize(size_t(vertices.columnStart(e) - vertices.columnStart(b)) * 12);
            char* dst = s.data();
            for (int64_t c = b; c < e; ++c)
                vertices.forEachInColumn(c, [&](int64_t i, int64_t j, int64_t k) {
                    const Vec3f p = position(i, j, k);
                    const float xyz[3] = {p.x, p.y, p.z};
                    std::memcpy(dst, xyz, 12);
                    dst += 12;
                });
        } else {
            for (int64_t c = b; c < e; ++c)
                vertices.forEachInColumn(c, [&](int64_t i, int64_t j, int64_t k) {
                    const Vec3f p = position(i, j, k);
                    s += "v ";
                    appendFloat(s, p.x);
                    s += ' ';
                    appendFloat(s, p.y);
                    s += ' ';
                    appendFloat(s, p.z);
                    s += '\n';
                });
        }
    });
    for (const FaceSet& fs : faceSets) {
        writeChunked(out, fs.grid.bits.columnCount(), kGrain, [&](int64_t b, int64_t e, std::string& s) {
            if (ply) {
                s.resize(size_t(fs.columnStart[size_t(e)] - fs.columnStart[size_t(b)]) * 17);
                char* dst = s.data();
                for (int64_t c = b; c < e; ++c)
                    fs.forEachInColumn(
                        c, [&](const Vec3i& p0, const Vec3i& p1, const Vec3i& p2, const Vec3i& p3) {
                            const int32_t quad[4] = {int32_t(index(p0)), int32_t(index(p1)),
                                                     int32_t(index(p2)), int32_t(index(p3))};
                            *dst++ = 4;
                            std::memcpy(dst, quad, 16);
                            dst += 16;
                        });
            } else {
                for (int64_t c = b; c < e; ++c)
                    fs.forEachInColumn(
                        c, [&](const Vec3i& p0, const Vec3i& p1, const Vec3i& p2, const Vec3i& p3) {
                            s += 'f';
                            for (const Vec3i* p : {&p0, &p1, &p2, &p3}) {
                                s += ' ';
                                appendInt(s, index(*p) + 1);
                            }
                            s += '\n';
                        });
            }
        });
    }
}

} // namespace voxfx::detail
