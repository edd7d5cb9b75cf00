// voxfx — density map and normals (Eisemann & Décoret, "Single-Pass GPU Solid Voxelization for
// Real-Time Applications", GI 2008, §6 "Density estimation": the 2x2x2 box filter by pairwise
// SWAR sums along the column plus sums over neighbour columns, repeated for larger power-of-two
// kernels; normals from the density gradient by central differences). The octahedral normal
// code follows Meyer et al., "On Floating-Point Normal Vectors", EGSR 2010, §3.
#include "voxfx/density.hpp"

#include <algorithm>
#include <cmath>

#ifdef __AVX2__
#include <immintrin.h>
#endif

#include "grid/density_kernels.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

DensityGrid::DensityGrid(int level, int64_t w, int64_t h, int64_t d) {
    if (level < 1 || level > 5) fail("density level must lie in 1..5 (kernels 2..32), got ", level);
    if (w <= 0 || h <= 0 || d <= 0)
        fail("density grid dimensions must be positive, got ", w, " x ", h, " x ", d);
    level_ = level;
    w_ = w;
    h_ = h;
    d_ = d;
    const int64_t lanes = lanesPerWord();
    wpc_ = (d + lanes - 1) / lanes;
    checkMemory(uint64_t(w * h * wpc_) * 8, "the density grid");
    storage_ = BitGrid(w * h * wpc_, 1, 64);
}

uint64_t DensityGrid::total() const {
    uint64_t sum = 0;
    for (int64_t y = 0; y < h_; ++y)
        for (int64_t x = 0; x < w_; ++x)
            for (int64_t s = 0; s < d_; ++s) sum += count(x, y, s);
    return sum;
}

namespace {

using detail::DensityColumnBlock;

// Calls body(X, Y, block, out) for every output column, rows of columns per parallel task (no
// divisions per column).
template <class Body>
void forEachOutputColumn(const uint64_t* words, int64_t W, int64_t H, int64_t P, uint64_t* dst, int64_t Wo,
                         int64_t Ho, int64_t Po, Body body) {
    parallelFor(0, Ho, std::max<int64_t>(1, 1024 / Wo), [&](int64_t first, int64_t last) {
        for (int64_t Y = first; Y < last; ++Y)
            for (int64_t X = 0; X < Wo; ++X)
                body(DensityColumnBlock(words, W, H, P, X, Y), dst + (Y * Wo + X) * Po);
    });
}

#ifdef __AVX2__
// The level-1 step on four input words k .. k + 3 at a time (AVX2), for k < end in steps of four;
// returns where it stopped. The same E and O sums as densityLevel1Words; the output nibbles are then
// interleaved with byte operations instead of spreading: output byte 2b holds cells 4b, 4b + 1
// = E nibble 2b, O nibble 2b (A below), byte 2b + 1 holds E, O nibble 2b + 1 (B), so an output
// word pair is the byte interleave of A and B (unpack within 128-bit lanes, then a lane permute
// puts the four input words' outputs in order).
int64_t level1Avx2(const DensityColumnBlock& blk, int64_t end, uint64_t* o) {
    const __m256i bits01 = _mm256_set1_epi64x(int64_t(detail::kDensityBits01)),
                  nib01 = _mm256_set1_epi64x(int64_t(detail::kDensityNibble01));
    const __m256i lowNib = _mm256_set1_epi8(0x0F), highNib = _mm256_set1_epi8(int8_t(0xF0));
    __m256i keep[4];
    for (int i = 0; i < 4; ++i) keep[i] = _mm256_set1_epi64x(int64_t(blk.keep[i]));
    int64_t k = 0;
    for (; k + 4 <= end; k += 4) {
        __m256i E = _mm256_setzero_si256(), O = _mm256_setzero_si256();
        for (int i = 0; i < 4; ++i) {
            const __m256i w = _mm256_and_si256(
                _mm256_loadu_si256(reinterpret_cast<const __m256i*>(blk.col[i] + k)), keep[i]);
            const __m256i p = _mm256_add_epi64(_mm256_and_si256(w, bits01),
                                               _mm256_and_si256(_mm256_srli_epi64(w, 1), bits01));
            E = _mm256_add_epi64(E, _mm256_and_si256(p, nib01));
            O = _mm256_add_epi64(O, _mm256_and_si256(_mm256_srli_epi64(p, 2), nib01));
        }
        const __m256i A =
            _mm256_or_si256(_mm256_and_si256(E, lowNib), _mm256_slli_epi64(_mm256_and_si256(O, lowNib), 4));
        const __m256i B =
            _mm256_or_si256(_mm256_and_si256(_mm256_srli_epi64(E, 4), lowNib), _mm256_and_si256(O, highNib));
        const __m256i U = _mm256_unpacklo_epi8(A, B), V = _mm256_unpackhi_epi8(A, B);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + 2 * k), _mm256_permute2x128_si256(U, V, 0x20));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + 2 * k + 4), _mm256_permute2x128_si256(U, V, 0x31));
    }
    return k;
}
#endif

// Level 1 from bits (densityLevel1Words: input word k of the block gives output words 2k and
// 2k + 1).
void densityLevel1(const BitGrid& grid, DensityGrid& out) {
    const int64_t W = grid.width(), H = grid.height(), P = grid.wordsPerColumn();
    const int64_t Wo = out.width(), Ho = out.height(), Po = out.wordsPerColumn();
    forEachOutputColumn(grid.words(), W, H, P, out.words(), Wo, Ho, Po,
                        [&](const DensityColumnBlock& blk, uint64_t* o) {
                            // Only the last input word may have its second half fall beyond the
                            // column (then it is zero). A branch-free main loop lets the compiler
                            // vectorize over k.
                            const int64_t pairs = std::min(P, Po / 2);
                            int64_t k = 0;
#ifdef __AVX2__
                            k = level1Avx2(blk, pairs, o);
#endif
                            for (; k < pairs; ++k) detail::densityLevel1Words(blk, k, o[2 * k], o[2 * k + 1]);
                            if (pairs < P) {
                                uint64_t hi;
                                detail::densityLevel1Words(blk, pairs, o[2 * pairs], hi);
                            }
                        });
}

// Level L+1 from level L (densityCoarsenWord: input word k of the block gives output word k).
void densityCoarsen(const DensityGrid& in, DensityGrid& out) {
    const int64_t W = in.width(), H = in.height(), P = in.wordsPerColumn();
    const int64_t Wo = out.width(), Ho = out.height(), Po = out.wordsPerColumn();
    const int b = in.laneBits();
    const uint64_t even = detail::densityEvenLanes(b);
    forEachOutputColumn(in.words(), W, H, P, out.words(), Wo, Ho, Po,
                        [&](const DensityColumnBlock& blk, uint64_t* o) {
                            for (int64_t k = 0; k < P; ++k)
                                o[k] = detail::densityCoarsenWord(blk, k, b, even);
                        });
}

} // namespace

void computeDensity(const BitGrid& grid, DensityGrid& out, const DensityOptions& options) {
    if (options.level < 1 || options.level > 5)
        fail("density level must lie in 1..5 (kernels 2..32), got ", options.level);
    if (grid.empty()) {
        out = DensityGrid();
        return;
    }
    const int64_t w1 = (grid.width() + 1) / 2, h1 = (grid.height() + 1) / 2, d1 = (grid.depth() + 1) / 2;
    withThreads(options.threads, [&] {
        if (options.level == 1) {
            if (out.level() != 1 || out.width() != w1 || out.height() != h1 || out.depth() != d1)
                out = DensityGrid(1, w1, h1, d1);
            densityLevel1(grid, out);
            return;
        }
        DensityGrid cur(1, w1, h1, d1);
        densityLevel1(grid, cur);
        while (cur.level() < options.level) {
            DensityGrid next(cur.level() + 1, (cur.width() + 1) / 2, (cur.height() + 1) / 2,
                             (cur.depth() + 1) / 2);
            densityCoarsen(cur, next);
            cur = std::move(next);
        }
        out = std::move(cur);
    });
}

DensityGrid computeDensity(const BitGrid& grid, const DensityOptions& options) {
    DensityGrid out;
    computeDensity(grid, out, options);
    return out;
}

DensityGrid coarsenDensity(const DensityGrid& density, int threads) {
    if (density.empty()) return {};
    if (density.level() >= 5) fail("density level 5 (kernel 32) is the coarsest supported");
    DensityGrid next(density.level() + 1, (density.width() + 1) / 2, (density.height() + 1) / 2,
                     (density.depth() + 1) / 2);
    withThreads(threads, [&] { densityCoarsen(density, next); });
    return next;
}

void occupancyField(const DensityGrid& density, std::span<float> out) {
    if (int64_t(out.size()) != density.cellCount())
        fail("occupancy field needs ", density.cellCount(), " values, the output holds ", out.size());
    const int64_t W = density.width(), D = density.depth();
    const float scale = 1.0f / float(density.maxCount());
    parallelFor(0, density.columnCount(), 1024, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c)
            for (int64_t s = 0; s < D; ++s)
                out[size_t(c * D + s)] = float(density.count(c % W, c / W, s)) * scale;
    });
}

std::vector<float> occupancyField(const DensityGrid& density) {
    std::vector<float> out(size_t(density.cellCount()));
    occupancyField(density, out);
    return out;
}

Vec3f densityGradient(const DensityGrid& density, int64_t x, int64_t y, int64_t s) {
    auto c = [&](int64_t i, int64_t j, int64_t k) { return float(density.countOrZero(i, j, k)); };
    return {0.5f * (c(x + 1, y, s) - c(x - 1, y, s)), 0.5f * (c(x, y + 1, s) - c(x, y - 1, s)),
            0.5f * (c(x, y, s + 1) - c(x, y, s - 1))};
}

Vec3f densityNormal(const DensityGrid& density, int64_t x, int64_t y, int64_t s) {
    return normalize(-densityGradient(density, x, y, s));
}

namespace {
// The eight cells around p (cell centres at +0.5) and their trilinear weights.
struct Trilinear {
    int64_t i0, j0, k0;
    double fx, fy, fz;
    explicit Trilinear(const Vec3d& p) {
        const double u = p.x - 0.5, v = p.y - 0.5, w = p.z - 0.5;
        // Clamp far-away points before converting to integers (the cells there are all 0).
        const double lim = 9.0e15;
        const double cu = std::clamp(std::floor(u), -lim, lim), cv = std::clamp(std::floor(v), -lim, lim),
                     cw = std::clamp(std::floor(w), -lim, lim);
        i0 = int64_t(cu);
        j0 = int64_t(cv);
        k0 = int64_t(cw);
        fx = std::clamp(u - cu, 0.0, 1.0);
        fy = std::clamp(v - cv, 0.0, 1.0);
        fz = std::clamp(w - cw, 0.0, 1.0);
    }
    double weight(int corner) const {
        return ((corner & 1) ? fx : 1 - fx) * ((corner & 2) ? fy : 1 - fy) * ((corner & 4) ? fz : 1 - fz);
    }
};
bool outsideBy(const DensityGrid& d, const Vec3d& p, double margin) {
    return p.x < -margin || p.y < -margin || p.z < -margin || p.x > double(d.width()) + margin ||
           p.y > double(d.height()) + margin || p.z > double(d.depth()) + margin;
}
} // namespace

float sampleOccupancy(const DensityGrid& density, const Vec3d& p) {
    if (!isFinite(p) || density.empty() || outsideBy(density, p, 1.0)) return 0.0f;
    const Trilinear t(p);
    double sum = 0;
    for (int corner = 0; corner < 8; ++corner)
        sum += t.weight(corner) * double(density.countOrZero(t.i0 + (corner & 1), t.j0 + ((corner >> 1) & 1),
                                                             t.k0 + ((corner >> 2) & 1)));
    return float(sum / double(density.maxCount()));
}

Vec3f sampleNormal(const DensityGrid& density, const Vec3d& p) {
    if (!isFinite(p) || density.empty() || outsideBy(density, p, 2.0)) return {};
    const Trilinear t(p);
    // The counts of the 4 x 4 x 4 block around the eight cells (their six neighbours each):
    // block[i][j][k] = count(i0 - 1 + i, j0 - 1 + j, k0 - 1 + k), read column by column when the
    // block lies inside the grid, else through countOrZero.
    float block[4][4][4];
    const bool inside = t.i0 >= 1 && t.j0 >= 1 && t.k0 >= 1 && t.i0 + 2 < density.width() &&
                        t.j0 + 2 < density.height() && t.k0 + 2 < density.depth();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) {
                const int64_t x = t.i0 - 1 + i, y = t.j0 - 1 + j, s = t.k0 - 1 + k;
                block[i][j][k] = float(inside ? density.count(x, y, s) : density.countOrZero(x, y, s));
            }
    Vec3d g;
    for (int corner = 0; corner < 8; ++corner) {
        const int i = 1 + (corner & 1), j = 1 + ((corner >> 1) & 1), k = 1 + ((corner >> 2) & 1);
        const Vec3d gc{0.5 * (block[i + 1][j][k] - block[i - 1][j][k]),
                       0.5 * (block[i][j + 1][k] - block[i][j - 1][k]),
                       0.5 * (block[i][j][k + 1] - block[i][j][k - 1])};
        g += gc * t.weight(corner);
    }
    return Vec3f(normalize(-g));
}

uint16_t encodeNormalOct16(const Vec3f& n) {
    const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
    if (!(l1 > 0) || !std::isfinite(l1)) return kNoNormal;
    // Project onto the octahedron |x| + |y| + |z| = 1 and fold the lower half over the upper:
    //   (x, y) -> ((1 - |y|) sign x, (1 - |x|) sign y) when z < 0.
    float u = n.x / l1, v = n.y / l1;
    if (n.z < 0) {
        const float fu = (1 - std::fabs(v)) * (u >= 0 ? 1.0f : -1.0f);
        const float fv = (1 - std::fabs(u)) * (v >= 0 ? 1.0f : -1.0f);
        u = fu;
        v = fv;
    }
    // [-1, 1] -> 0..254 (127 is exactly 0); 255 is left free for kNoNormal.
    auto q = [](float a) { return uint16_t(std::clamp(std::lround((a + 1.0f) * 127.0f), 0l, 254l)); };
    return uint16_t(q(u) | (q(v) << 8));
}

Vec3f decodeNormalOct16(uint16_t code) {
    if (code == kNoNormal) return {};
    const float u = float(code & 0xFF) / 127.0f - 1.0f, v = float(code >> 8) / 127.0f - 1.0f;
    Vec3f n{u, v, 1.0f - std::fabs(u) - std::fabs(v)};
    if (n.z < 0) {
        const float fx = (1 - std::fabs(v)) * (u >= 0 ? 1.0f : -1.0f);
        const float fy = (1 - std::fabs(u)) * (v >= 0 ? 1.0f : -1.0f);
        n.x = fx;
        n.y = fy;
    }
    return normalize(n);
}

void quantizedNormals(const DensityGrid& density, std::span<uint16_t> out, int threads) {
    if (int64_t(out.size()) != density.cellCount())
        fail("quantized normals need ", density.cellCount(), " values, the output holds ", out.size());
    const int64_t W = density.width(), D = density.depth();
    withThreads(threads, [&] {
        parallelFor(0, density.columnCount(), 256, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c)
                for (int64_t s = 0; s < D; ++s)
                    out[size_t(c * D + s)] = encodeNormalOct16(densityNormal(density, c % W, c / W, s));
        });
    });
}

std::vector<uint16_t> quantizedNormals(const DensityGrid& density, int threads) {
    std::vector<uint16_t> out(size_t(density.cellCount()));
    quantizedNormals(density, out, threads);
    return out;
}

Frame densityFrame(const Frame& fine, int level) {
    if (fine.isPerspective() || fine.slicing() != Slicing::Uniform)
        fail("density frames need an orthographic, uniformly sliced grid");
    if (level < 1 || level > 5) fail("density level must lie in 1..5, got ", level);
    const int64_t k = int64_t(1) << level;
    const int64_t w = (fine.width() + k - 1) / k, h = (fine.height() + k - 1) / k,
                  d = (fine.depth() + k - 1) / k;
    const Axis a = fine.axis();
    const Vec3d cell = fine.cellSize();
    Vec3i n;
    n[columnXAxis(a)] = w;
    n[columnYAxis(a)] = h;
    n[sliceAxis(a)] = d;
    Box3d box;
    box.lo = fine.box().lo;
    for (int i = 0; i < 3; ++i) box.hi[i] = box.lo[i] + cell[i] * double(k) * double(n[i]);
    return Frame::orthographic(box, a, w, h, d);
}

Vec3d worldFromGridNormal(const Frame& frame, const Vec3d& gridNormal) {
    const Vec3d cell = frame.cellSize();
    const Axis a = frame.axis();
    Vec3d w;
    w[columnXAxis(a)] = gridNormal.x / cell[columnXAxis(a)];
    w[columnYAxis(a)] = gridNormal.y / cell[columnYAxis(a)];
    w[sliceAxis(a)] = gridNormal.z / cell[sliceAxis(a)];
    return normalize(w);
}

} // namespace voxfx
