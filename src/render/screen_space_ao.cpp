// voxfx — screen-space ambient occlusion (render/screen_space_ao.hpp): GTAO, Jimenez et al. 2016,
// "Practical Real-Time Strategies for Accurate Indirect Occlusion", sections 4 (horizon search and
// the per-slice integral, eq. 10) and 5 (spatial interleaving with a 4x4 pattern and a 4x4 blur;
// the temporal part, which needs frames, is left out). Passes:
//   1. working buffer: the samples themselves, or per 2x2 block the mean of its samples where they
//      show one smooth surface, else the covered sample nearest the eye (a thin object in front
//      keeps its samples; the surface behind it finds its own in the neighbouring blocks at the
//      upsample);
//   2. per working pixel, `directions` slices, each with two horizons found by `steps` samples per
//      side, integrated in closed form; the sides walked in AVX2 lanes (two pixels' four sides at
//      once) on an 8-byte view-space copy of the working buffer, bit for bit the scalar walk
//      (ScreenSpaceOcclusionOptions::vectorWalk); skipped where no occluder lies within reach on
//      screen and within twice the radius in view depth, coplanar points of a flat mesh excepted
//      (skipTiles, per 8x8 tile; the G-buffer entries with flatMeshes): the search's output exactly;
//   3. links between neighbouring working pixels on one smooth surface, and a separable blur over
//      5 x 5 linked pixels, weights 1 2 2 2 1 (every phase of the 4x4 pattern gets the same weight,
//      so the pattern cancels on a smooth surface);
//   4. half resolution: a bilateral upsample (bilinear weights, where the four working pixels are
//      linked; else times geometric similarity).
#include "render/screen_space_ao.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>

#include "render/render_cache.hpp"
#include "render/shading.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

#if defined(__AVX2__)
#include <immintrin.h>
#define VOXFX_SSAO_AVX2 1
#else
#define VOXFX_SSAO_AVX2 0
#endif

namespace voxfx::detail {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr int kMaxDirections = 16, kMaxSteps = 32;
// The horizon search reaches 1.2 radii (at p's depth) on screen, so that a sample usually lies
// beyond the radius and the horizon is interpolated up to it (see occlusionAt); samples are spaced
// as the 1.5th power of their index, denser near p where contact occlusion changes fastest. Both
// chosen on the corner test (6 steps: mean error within the radius 0.027 with a reach of 1 and spacing
// power 2, 0.007 with these).
constexpr float kReach = 1.2f;
constexpr double kSpacingPower = 1.5;
// A walk sample's offset from its pixel's central ray counts 1/8192ths of a pixel (up to 4 pixels).
constexpr float kOffsetUnits = 8192;

// The 4x4 Bayer matrix: neighbouring pixels get distant pattern indices, so any 2x2 or 4x1 group
// spreads over the slice angles.
constexpr int kBayer[4][4] = {{0, 8, 2, 10}, {12, 4, 14, 6}, {3, 11, 1, 9}, {15, 7, 13, 5}};

// A working buffer, as the passes read it: per pixel (row-major) the position, the normal, whether
// it is covered and whether it occludes. Packed: position and flags in 16 bytes (the horizon search
// reads them together at scattered pixels: one cache line per sample instead of three), normals
// apart.
constexpr uint32_t kCovered = 1, kOccluder = 2;
using Sample = ScreenSpaceSample;
struct Packed {
    int64_t width = 0, height = 0;
    const Sample* sample = nullptr;
    const Vec3f* normals = nullptr;
    const ScreenSpaceWalkSample* walk = nullptr; ///< the horizon search's copy (walkSamples)
    /// Where the search may be skipped (skipTiles; null: nowhere): per working pixel its mesh, per
    /// 8x8 tile (tileColumns per row) its verdict.
    const int32_t* mesh = nullptr;
    const ScreenSpaceOcclusionScratch::Tile* tiles = nullptr;
    int64_t tileColumns = 0;
    // Whether working pixel (x, y), covered, skips the search (its visibility is then exactly 1).
    bool skips(int64_t x, int64_t y, int64_t i) const {
        if (!tiles) return false;
        const ScreenSpaceOcclusionScratch::Tile& t = tiles[(y >> 3) * tileColumns + (x >> 3)];
        return t.skipAll || (t.skipMesh >= 0 && mesh[i] == t.skipMesh);
    }
    bool covered(int64_t i) const { return sample[i].flags & kCovered; }
    bool occludes(int64_t i) const { return sample[i].flags == (kCovered | kOccluder); }
    const Vec3f& position(int64_t i) const { return sample[i].position; }
    const Vec3f& normal(int64_t i) const { return normals[i]; }
};

// The full-resolution samples the working buffer is made from, and what the upsample and its rare
// fallback (GTAO at one sample) read of them: by index as a buffer (as Packed), by (x, y) in the
// down- and upsample. `testNormal` is the normal the downsample's one-surface test compares,
// `upsampleNormal` the one the upsample's similarity weights take, and `meanNormal` the normal of a
// block of one surface (from the sum of its test normals and its mean position). Two sources: the caller's
// buffers (Spans), and the cells of a G-buffer (Cells).
struct Spans {
    int64_t width = 0, height = 0;
    const Vec3f* positions = nullptr;
    const Vec3f* normals = nullptr;
    const uint8_t* coverage = nullptr;
    const uint8_t* occluders = nullptr; ///< null: every covered sample occludes
    bool covered(int64_t i) const { return coverage[i]; }
    bool occludes(int64_t i) const { return coverage[i] && (!occluders || occluders[i]); }
    const Vec3f& position(int64_t i) const { return positions[i]; }
    const Vec3f& normal(int64_t i) const { return normals[i]; }
    bool covered(int64_t x, int64_t y) const { return covered(y * width + x); }
    bool occludes(int64_t x, int64_t y) const { return occludes(y * width + x); }
    Vec3f position(int64_t x, int64_t y) const { return positions[y * width + x]; }
    Vec3f normal(int64_t x, int64_t y) const { return normals[y * width + x]; }
    Vec3f testNormal(int64_t x, int64_t y) const { return normals[y * width + x]; }
    Vec3f testNormal(int64_t x, int64_t y, const Vec3f&) const { return normals[y * width + x]; }
    Vec3f normalAt(int64_t x, int64_t y, const Vec3f&) const { return normals[y * width + x]; }
    Vec3f upsampleNormal(int64_t x, int64_t y) const { return normals[y * width + x]; }
    static constexpr bool kMeshes = false; // the buffers do not say
    int32_t meshOf(int64_t, int64_t) const { return -1; }
    Vec3f meanNormal(const Vec3f& sum, int64_t, int64_t, const Vec3f&) const {
        return length(sum) > 0 ? normalize(sum) : Vec3f{0, 0, 0};
    }
};

// The renderer's samples: cell (x, y) of a G-buffer of `adaptive` x `adaptive` samples per cell is
// its sample (x a + a / 2, y a + a / 2), the one the shading pass shades. Its position comes from
// the depth (a multiply-add per coordinate: the eye ray's offsets per cell column and row are kept),
// its normals only where asked: the face normal for the one-surface test from the triangle's compact
// record (TriangleTag, with its mesh and whether it occludes: 16 bytes a triangle, read at random,
// instead of the 84-byte basis and two tables), the interpolated one (interpolatedNormal, as the
// shading pass's) from its basis for the working pixel and the upsample's slow path, except on a
// flat triangle (kTagFlat: its corner normals within 0.01 rad of its face normal; the forest's leaves,
// to float rounding), whose face normal from the record stands for its shading normal. So the downsample
// evaluates one shading normal per block, not four, and visits no basis on the forest's leaves.
struct Cells {
    int64_t width = 0, height = 0; ///< cells
    const GBuffer* g = nullptr;
    const SceneGeometry* geometry = nullptr;
    const TriangleBasis* bases = nullptr;
    std::vector<TriangleTag> ownTags; ///< made here where the caller has none
    const TriangleTag* tags = nullptr;
    int adaptive = 1;
    Vec3f eye, right, up, forward;
    std::vector<float> columnTan, rowTan; ///< the eye ray's offset along right, up per unit depth

    Cells(const GBuffer& gbuffer, const SceneGeometry& geo, std::span<const TriangleBasis> b,
          std::span<const uint8_t> opaqueMaterial, int a, std::span<const TriangleTag> triangleTagsOrNone)
        : width(gbuffer.frame.width() / a), height(gbuffer.frame.height() / a), g(&gbuffer), geometry(&geo),
          bases(b.data()), adaptive(a), eye(gbuffer.frame.eye()), right(gbuffer.frame.right()),
          up(gbuffer.frame.up()), forward(gbuffer.frame.forward()) {
        if (triangleTagsOrNone.empty()) {
            ownTags = triangleTags(geo, b, opaqueMaterial);
            tags = ownTags.data();
        } else {
            tags = triangleTagsOrNone.data();
        }
        const Frame& f = gbuffer.frame;
        columnTan.resize(size_t(width));
        rowTan.resize(size_t(height));
        for (int64_t x = 0; x < width; ++x)
            columnTan[size_t(x)] =
                float(dot(f.worldFromGrid({double(x * a + a / 2) + 0.5, 0.5, 1.0}) - f.eye(), f.right()));
        for (int64_t y = 0; y < height; ++y)
            rowTan[size_t(y)] =
                float(dot(f.worldFromGrid({0.5, double(y * a + a / 2) + 0.5, 1.0}) - f.eye(), f.up()));
    }
    std::size_t sample(int64_t x, int64_t y) const {
        return std::size_t((y * adaptive + adaptive / 2) * g->frame.width() + x * adaptive + adaptive / 2);
    }
    uint32_t triangle(int64_t x, int64_t y) const { return g->triangle[sample(x, y)]; }
    static constexpr bool kMeshes = true;
    int32_t meshOf(int64_t x, int64_t y) const { return int32_t(tags[triangle(x, y)].mesh & kTagMesh); }
    bool covered(int64_t x, int64_t y) const { return triangle(x, y) != GBuffer::kNone; }
    bool occludes(int64_t x, int64_t y) const {
        const uint32_t t = triangle(x, y);
        return t != GBuffer::kNone && (tags[t].mesh & kTagOccludes);
    }
    Vec3f position(int64_t x, int64_t y) const {
        const float z = g->depth[sample(x, y)];
        return eye + (right * columnTan[size_t(x)] + up * rowTan[size_t(y)] + forward) * z;
    }
    // The face normal, turned towards the eye.
    Vec3f testNormal(int64_t x, int64_t y) const { return testNormal(x, y, position(x, y)); }
    // The same, where the caller has its position (`at`, position(x, y)).
    Vec3f testNormal(int64_t x, int64_t y, const Vec3f& at) const {
        const Vec3f n = tags[triangle(x, y)].normal;
        return dot(n, eye - at) < 0 ? -n : n;
    }
    // The shading normal at `at` on the triangle of cell (x, y), turned as surfaceFromBasis turns it.
    // A flat triangle's (kTagFlat) is its face normal, turned so, without a visit to its basis.
    Vec3f normalAt(int64_t x, int64_t y, const Vec3f& at) const {
        const uint32_t t = triangle(x, y);
        if (tags[t].mesh & kTagFlat) return testNormal(x, y, at);
        const TriangleBasis& basis = bases[t];
        const Vec3f n = interpolatedNormal(basis, at - basis.a);
        Vec3f ng = basis.normal;
        if (dot(ng, eye - at) < 0) ng = -ng;
        return dot(n, ng) < 0 ? -n : n;
    }
    Vec3f normal(int64_t x, int64_t y) const { return normalAt(x, y, position(x, y)); }
    // The upsample's similarity weights take the face normal: the interpolated one moves them little
    // and costs a visit to the triangle's vertices, for every cell off the upsample's fast path.
    Vec3f upsampleNormal(int64_t x, int64_t y) const { return testNormal(x, y); }
    Vec3f meanNormal(const Vec3f&, int64_t bestX, int64_t bestY, const Vec3f& meanPosition) const {
        return normalAt(bestX, bestY, meanPosition);
    }
    // By index, as a buffer (the upsample's fallback).
    bool covered(int64_t i) const { return covered(i % width, i / width); }
    bool occludes(int64_t i) const { return occludes(i % width, i / width); }
    Vec3f position(int64_t i) const { return position(i % width, i / width); }
    Vec3f normal(int64_t i) const { return normal(i % width, i / width); }
};

// What every pixel of one working buffer shares.
struct Params {
    Vec3f eye, right, up, forward;
    float pixelsPerTan = 0; ///< working pixels per unit of (lateral offset / view depth)
    float pixelSize = 0;    ///< 1 / pixelsPerTan: a working pixel's footprint per unit of depth
    float radius = 0, radius2 = 0, sinBias2 = 0; ///< sinBias2: sin^2 of the bias angle
    int directions = 0, steps = 0;
    bool scalarWalk =
        false; ///< the horizon search one side at a time (ScreenSpaceOcclusionOptions::vectorWalk)
    // The central ray of working pixel (x, y) is right tx + up ty + forward (per unit of depth), with
    // tx = txBase + x txStep, ty = tyBase + y tyStep; a walk sample's offsets count txStep / 8192.
    float txBase = 0, tyBase = 0, txStep = 0, tyStep = 0, txQuant = 0, tyQuant = 0;
    // Per pattern index: the slices' screen directions and the steps' distances as fractions of the
    // radius in pixels.
    std::array<std::array<float, kMaxDirections>, 16> dirX{}, dirY{};
    std::array<std::array<float, kMaxSteps>, 16> stepFraction{};
};

Params makeParams(const Frame& camera, int scale, const ScreenSpaceOcclusionOptions& o) {
    Params p;
    p.eye = Vec3f(camera.eye());
    p.right = Vec3f(camera.right());
    p.up = Vec3f(camera.up());
    p.forward = Vec3f(camera.forward());
    p.pixelsPerTan = float(0.5 * double(camera.height()) / (camera.tanHalfFovY() * scale));
    p.radius = float(o.radius);
    p.pixelSize = 1 / p.pixelsPerTan;
    p.radius2 = p.radius * p.radius;
    p.sinBias2 = float(std::sin(o.bias) * std::sin(o.bias));
    p.directions = o.directions;
    p.steps = o.steps;
    p.scalarWalk = !o.vectorWalk || !VOXFX_SSAO_AVX2;
    const auto tangent = [&](double gx, double gy) {
        const Vec3d w = camera.worldFromGrid({gx, gy, 1.0}) - camera.eye();
        return std::array<double, 2>{dot(w, camera.right()), dot(w, camera.up())};
    };
    const auto t0 = tangent(0.5 * scale, 0.5 * scale), t1 = tangent(1.5 * scale, 1.5 * scale);
    p.txBase = float(t0[0]), p.tyBase = float(t0[1]);
    p.txStep = float(t1[0] - t0[0]), p.tyStep = float(t1[1] - t0[1]);
    p.txQuant = p.txStep / kOffsetUnits, p.tyQuant = p.tyStep / kOffsetUnits;
    for (int k = 0; k < 16; ++k) {
        // Slice angles: 16 rotations by sixteenths of the spacing pi / directions; step offsets: a
        // second permutation of the pattern (5k + 3 mod 16), so angle and offset do not go together.
        for (int s = 0; s < o.directions; ++s) {
            const double phi = M_PI * (s + (k + 0.5) / 16) / o.directions;
            p.dirX[size_t(k)][size_t(s)] = float(std::cos(phi));
            p.dirY[size_t(k)][size_t(s)] = float(std::sin(phi));
        }
        const double jitter = (double((5 * k + 3) % 16) + 0.5) / 16;
        for (int i = 0; i < o.steps; ++i) {
            const double u = (i + jitter) / o.steps;
            p.stepFraction[size_t(k)][size_t(i)] = float(std::pow(u, kSpacingPower));
        }
    }
    return p;
}

// The slice's visible part between the tangent-side limit and horizon h (angle from the view vector,
// cos h = ch, sin h = sh), for the projected normal at angle gamma (paper, eq. 10, one side):
// (cos gamma + 2 h sin gamma - cos(2 h - gamma)) / 4, with cos(2h - gamma) expanded so that only
// h itself needs an inverse cosine.
inline float arc(float h, float ch, float sh, float cosG, float sinG) {
    const float cos2hMinusG = (2 * ch * ch - 1) * cosG + 2 * sh * ch * sinG;
    return 0.25f * (cosG + 2 * h * sinG - cos2hMinusG);
}

// acos on [-1, 1] to about 7e-5 radians (Abramowitz and Stegun 4.4.45); the horizons' angles enter
// the integral linearly, so this is far below the method's own error.
inline float fastAcos(float x) {
    const float a = std::fabs(x);
    const float r = std::sqrt(std::max(0.0f, 1 - a)) *
                    (1.5707288f + a * (-0.2121144f + a * (0.0742610f - 0.0187293f * a)));
    return x >= 0 ? r : kPi - r;
}

// One side of a slice of GTAO at a working pixel: samples along the screen direction (sx, sy) up
// to `reach` working pixels, spaced by `fraction`, raise the horizon from the pixel's point P (unit
// normal N, unit direction to the eye V). In view space (right, up, forward from the eye), where the
// walk samples (Packed::walk) give their points.
template <class Buffer> struct HorizonWalk {
    const Buffer& b;
    const Params& p;
    const std::array<float, kMaxSteps>& fraction;
    int64_t here; // the pixel's index
    float cx, cy; // its centre
    float reach;  // working pixels
    Vec3f P, N, V;

    // Working pixel (x, y)'s point in view space from its walk sample w (which occludes).
    Vec3f viewPoint(const ScreenSpaceWalkSample& w, int64_t x, int64_t y) const {
        const float tx = (p.txBase + float(x) * p.txStep) + float(w.offsetX) * p.txQuant;
        const float ty = (p.tyBase + float(y) * p.tyStep) + float(w.offsetY) * p.tyQuant;
        return {tx * w.depth, ty * w.depth, w.depth};
    }

    // A point d (from P) raises the horizon (the cosine of its angle from V) unless it lies at most
    // `bias` above the tangent plane (the surface itself). Compared through squares with their signs
    // (c > h iff c|c| > h|h|), so that only a sample that raises the horizon costs a square root.
    void raiseBy(const Vec3f& d, float d2, float& horizon, bool& raised) const {
        const float dn = dot(d, N);
        if (!(dn > 0 && dn * dn > p.sinBias2 * d2)) return;
        const float dv = dot(d, V), h = horizon;
        if (dv * std::fabs(dv) > h * std::fabs(h) * d2) {
            horizon = dv / std::sqrt(d2);
            raised = true;
        }
    }

    // Walks the side, raising `horizon`; whether it was raised.
    bool raise(float sx, float sy, float& horizon) const {
        const float width = float(b.width), height = float(b.height);
        bool raised = false;
        Vec3f previous;
        bool previousInside = false; // the last sample was an occluder within the radius
        for (int i = 0; i < p.steps; ++i) {
            const float t = reach * fraction[size_t(i)];
            const float fx = cx + sx * t, fy = cy + sy * t;
            // No data beyond the image (on it, truncation is the floor).
            if (!(fx >= 0 && fy >= 0 && fx < width && fy < height)) break;
            const int64_t x = int64_t(fx), y = int64_t(fy), q = y * b.width + x;
            if (q == here) continue;
            const ScreenSpaceWalkSample& sample = b.walk[q];
            if (!(sample.depth > 0)) { // not an occluder
                previousInside = false;
                continue;
            }
            const Vec3f d = viewPoint(sample, x, y) - P;
            const float d2 = dot(d, d);
            if (d2 < p.radius2) {
                if (d2 > 0) raiseBy(d, d2, horizon, raised);
                previous = d;
                previousInside = true;
                continue;
            }
            // Beyond the radius after a sample within it: the highest occluder within the radius lies
            // between them on a surface that rises with the distance (a wall), so the point where the
            // segment between them crosses the sphere raises the horizon too. Without it the horizon
            // stops at the last sample inside, short of the radius by up to a step, and walls occlude
            // too little. Segments longer than the radius span a gap between surfaces, not a surface.
            if (previousInside) {
                const Vec3f e = d - previous;
                const float a = dot(e, e);
                if (a < p.radius2) {
                    const float bh = dot(previous, e), c = dot(previous, previous) - p.radius2;
                    const float u = (-bh + std::sqrt(std::max(0.0f, bh * bh - a * c))) / a;
                    const Vec3f crossing = previous + e * std::clamp(u, 0.0f, 1.0f);
                    raiseBy(crossing, dot(crossing, crossing), horizon, raised);
                }
            }
            previousInside = false;
        }
        return raised;
    }
};

#if VOXFX_SSAO_AVX2
// The four sides of two slices of two points at once, one per lane of an AVX register (lanes 0-3
// point a's, 4-7 point b's; a lone point fills both halves), with `raise`'s arithmetic operation
// for operation, so the horizons are bit for bit the scalar walk's: the samples' branches
// (occluder or not, inside the radius or not, raised or not) become masks, which the scalar walk
// mispredicts about once a side, and the steps cost half the instructions per point of four lanes.
// Sample indices in 32 bits: the callers check that the buffer's fit.
template <class Buffer> struct HorizonWalk8 {
    const HorizonWalk<Buffer>& a;
    const HorizonWalk<Buffer>& b;

    static __m256 pair(float lo, float hi) {
        return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_set1_ps(lo)), _mm_set1_ps(hi), 1);
    }
    static __m256i pairInt(int32_t lo, int32_t hi) {
        return _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_set1_epi32(lo)), _mm_set1_epi32(hi), 1);
    }
    static __m256 select(__m256 mask, __m256 x, __m256 y) {
        return _mm256_or_ps(_mm256_and_ps(mask, x), _mm256_andnot_ps(mask, y));
    }
    static __m256 dot3(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
        return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)),
                             _mm256_mul_ps(az, bz));
    }
    static __m256 absolute(__m256 v) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), v); }

    struct Lanes {
        __m256 horizon, raised;
        __m256 nx, ny, nz, vx, vy, vz; // the points' N and V
    };
    void raiseBy(__m256 mask, __m256 dx, __m256 dy, __m256 dz, __m256 d2, Lanes& l) const {
        const __m256 dn = dot3(dx, dy, dz, l.nx, l.ny, l.nz);
        mask = _mm256_and_ps(
            mask, _mm256_and_ps(_mm256_cmp_ps(dn, _mm256_setzero_ps(), _CMP_GT_OQ),
                                _mm256_cmp_ps(_mm256_mul_ps(dn, dn),
                                              _mm256_mul_ps(_mm256_set1_ps(a.p.sinBias2), d2), _CMP_GT_OQ)));
        if (!_mm256_movemask_ps(mask)) return;
        const __m256 dv = dot3(dx, dy, dz, l.vx, l.vy, l.vz);
        const __m256 h = l.horizon;
        const __m256 higher =
            _mm256_and_ps(mask, _mm256_cmp_ps(_mm256_mul_ps(dv, absolute(dv)),
                                              _mm256_mul_ps(_mm256_mul_ps(h, absolute(h)), d2), _CMP_GT_OQ));
        l.horizon = select(higher, _mm256_div_ps(dv, _mm256_sqrt_ps(d2)), h);
        l.raised = _mm256_or_ps(l.raised, higher);
    }
    void raiseAtCrossing(__m256 mask, __m256 dx, __m256 dy, __m256 dz, __m256 prevX, __m256 prevY,
                         __m256 prevZ, Lanes& l) const {
        const __m256 radius2 = _mm256_set1_ps(a.p.radius2), zero = _mm256_setzero_ps(),
                     one = _mm256_set1_ps(1.0f);
        const __m256 ex = _mm256_sub_ps(dx, prevX), ey = _mm256_sub_ps(dy, prevY),
                     ez = _mm256_sub_ps(dz, prevZ);
        const __m256 e2 = dot3(ex, ey, ez, ex, ey, ez);
        mask = _mm256_and_ps(mask, _mm256_cmp_ps(e2, radius2, _CMP_LT_OQ));
        if (!_mm256_movemask_ps(mask)) return;
        const __m256 bh = dot3(prevX, prevY, prevZ, ex, ey, ez);
        const __m256 c = _mm256_sub_ps(dot3(prevX, prevY, prevZ, prevX, prevY, prevZ), radius2);
        const __m256 root =
            _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(_mm256_mul_ps(bh, bh), _mm256_mul_ps(e2, c)), zero));
        __m256 u = _mm256_div_ps(_mm256_add_ps(_mm256_xor_ps(bh, _mm256_set1_ps(-0.0f)), root), e2);
        u = select(_mm256_cmp_ps(u, zero, _CMP_LT_OQ), zero,
                   select(_mm256_cmp_ps(one, u, _CMP_LT_OQ), one, u));
        const __m256 cx = _mm256_add_ps(prevX, _mm256_mul_ps(ex, u)),
                     cy = _mm256_add_ps(prevY, _mm256_mul_ps(ey, u)),
                     cz = _mm256_add_ps(prevZ, _mm256_mul_ps(ez, u));
        raiseBy(mask, cx, cy, cz, dot3(cx, cy, cz, cx, cy, cz), l);
    }
    // The walk samples of the lanes' pixels (ix, iy) (dead lanes, not in `alive`: their point's own or
    // the first): their depths, and their offsets as floats; `self`: the lanes on their point's pixel.
    __m256 load(__m256i ix, __m256i iy, __m256 alive, __m256& self, __m256& offsetX, __m256& offsetY) const {
        const __m256i index =
            _mm256_add_epi32(_mm256_mullo_epi32(iy, _mm256_set1_epi32(int32_t(a.b.width))), ix);
        const __m256i live = _mm256_castps_si256(alive);
        const __m256i chosen =
            _mm256_or_si256(_mm256_and_si256(live, index),
                            _mm256_andnot_si256(live, pairInt(int32_t(a.here >= 0 ? a.here : 0),
                                                              int32_t(b.here >= 0 ? b.here : 0))));
        self = _mm256_castsi256_ps(_mm256_cmpeq_epi32(chosen, pairInt(int32_t(a.here), int32_t(b.here))));
        alignas(32) int32_t q[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(q), chosen);
        const ScreenSpaceWalkSample* walk = a.b.walk;
        __m128i s[8];
        for (int k = 0; k < 8; ++k) s[k] = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&walk[q[k]]));
        __m128 depth[2], offsets[2];
        for (int h = 0; h < 2; ++h) {
            const __m128 lo = _mm_castsi128_ps(_mm_unpacklo_epi64(s[4 * h], s[4 * h + 1]));
            const __m128 hi = _mm_castsi128_ps(_mm_unpacklo_epi64(s[4 * h + 2], s[4 * h + 3]));
            depth[h] = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
            offsets[h] = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1));
        }
        const __m256i o =
            _mm256_castps_si256(_mm256_insertf128_ps(_mm256_castps128_ps256(offsets[0]), offsets[1], 1));
        offsetX = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(o, 16), 16));
        offsetY = _mm256_cvtepi32_ps(_mm256_srai_epi32(o, 16));
        return _mm256_insertf128_ps(_mm256_castps128_ps256(depth[0]), depth[1], 1);
    }

    // sx, sy, horizon: 8 lanes each (a's four sides, then b's); the lanes raised as bits.
    int raise(const float* sx, const float* sy, float* horizon) const {
        const Params& p = a.p;
        const __m256 sxv = _mm256_loadu_ps(sx), syv = _mm256_loadu_ps(sy);
        const __m256 width = _mm256_set1_ps(float(a.b.width)), height = _mm256_set1_ps(float(a.b.height));
        const __m256 px = pair(a.P.x, b.P.x), py = pair(a.P.y, b.P.y), pz = pair(a.P.z, b.P.z);
        const __m256 cx = pair(a.cx, b.cx), cy = pair(a.cy, b.cy);
        const __m256 radius2 = _mm256_set1_ps(p.radius2), zero = _mm256_setzero_ps();
        Lanes l{_mm256_loadu_ps(horizon), zero,
                pair(a.N.x, b.N.x),       pair(a.N.y, b.N.y),
                pair(a.N.z, b.N.z),       pair(a.V.x, b.V.x),
                pair(a.V.y, b.V.y),       pair(a.V.z, b.V.z)};
        __m256 alive = _mm256_castsi256_ps(_mm256_set1_epi32(-1)), previousInside = zero;
        __m256 prevX = zero, prevY = zero, prevZ = zero;
        for (int i = 0; i < p.steps; ++i) {
            const __m256 t = pair(a.reach * a.fraction[size_t(i)], b.reach * b.fraction[size_t(i)]);
            const __m256 fx = _mm256_add_ps(cx, _mm256_mul_ps(sxv, t));
            const __m256 fy = _mm256_add_ps(cy, _mm256_mul_ps(syv, t));
            alive = _mm256_and_ps(alive, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(fx, zero, _CMP_GE_OQ),
                                                                     _mm256_cmp_ps(fy, zero, _CMP_GE_OQ)),
                                                       _mm256_and_ps(_mm256_cmp_ps(fx, width, _CMP_LT_OQ),
                                                                     _mm256_cmp_ps(fy, height, _CMP_LT_OQ))));
            if (!_mm256_movemask_ps(alive)) break;
            const __m256i ix = _mm256_cvttps_epi32(fx), iy = _mm256_cvttps_epi32(fy);
            __m256 self, offsetX, offsetY;
            const __m256 depth = load(ix, iy, alive, self, offsetX, offsetY);
            const __m256 active = _mm256_andnot_ps(self, alive);
            const __m256 act = _mm256_and_ps(active, _mm256_cmp_ps(depth, zero, _CMP_GT_OQ));
            const __m256 tx =
                _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(p.txBase),
                                            _mm256_mul_ps(_mm256_cvtepi32_ps(ix), _mm256_set1_ps(p.txStep))),
                              _mm256_mul_ps(offsetX, _mm256_set1_ps(p.txQuant)));
            const __m256 ty =
                _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(p.tyBase),
                                            _mm256_mul_ps(_mm256_cvtepi32_ps(iy), _mm256_set1_ps(p.tyStep))),
                              _mm256_mul_ps(offsetY, _mm256_set1_ps(p.tyQuant)));
            const __m256 dx = _mm256_sub_ps(_mm256_mul_ps(tx, depth), px),
                         dy = _mm256_sub_ps(_mm256_mul_ps(ty, depth), py), dz = _mm256_sub_ps(depth, pz);
            const __m256 d2 = dot3(dx, dy, dz, dx, dy, dz);
            const __m256 inside = _mm256_and_ps(act, _mm256_cmp_ps(d2, radius2, _CMP_LT_OQ));
            raiseBy(_mm256_and_ps(inside, _mm256_cmp_ps(d2, zero, _CMP_GT_OQ)), dx, dy, dz, d2, l);
            const __m256 crossing = _mm256_andnot_ps(inside, _mm256_and_ps(act, previousInside));
            if (_mm256_movemask_ps(crossing)) raiseAtCrossing(crossing, dx, dy, dz, prevX, prevY, prevZ, l);
            prevX = select(inside, dx, prevX), prevY = select(inside, dy, prevY),
            prevZ = select(inside, dz, prevZ);
            previousInside = _mm256_or_ps(_mm256_andnot_ps(active, previousInside), inside);
        }
        _mm256_storeu_ps(horizon, l.horizon);
        return _mm256_movemask_ps(l.raised);
    }
};
#endif

// The four sides of a pair of slices (lanes: screen directions sx, sy; horizons in and out; whether
// each was raised), at once (HorizonWalk8, the point in both halves) or one at a time (`scalar`): the
// same result bit for bit.
template <class Buffer>
void walkSides(const HorizonWalk<Buffer>& walk, bool scalar, const float* sx, const float* sy, float* horizon,
               bool* raised) {
#if VOXFX_SSAO_AVX2
    if (!scalar && walk.b.width * walk.b.height <= INT32_MAX) {
        float sx8[8], sy8[8], horizon8[8];
        for (int j = 0; j < 8; ++j) sx8[j] = sx[j & 3], sy8[j] = sy[j & 3], horizon8[j] = horizon[j & 3];
        const int bits = HorizonWalk8<Buffer>{walk, walk}.raise(sx8, sy8, horizon8);
        for (int j = 0; j < 4; ++j) horizon[j] = horizon8[j], raised[j] = (bits >> j) & 1;
        return;
    }
#else
    (void)scalar;
#endif
    for (int j = 0; j < 4; ++j) raised[j] = walk.raise(sx[j], sy[j], horizon[j]);
}

// One slice of GTAO at a point (unit normal N, unit direction to the eye V): the plane through the eye
// ray and the screen direction (dx, dy), spanned by V and `axis` (the screen direction in world, made
// orthogonal to V). Angles are measured from V, positive towards axis (the side of +(dx, dy) on
// screen). `valid` false: the slice is degenerate (it adds nothing).
struct Slice {
    bool valid = false;
    float weight = 0, cosG = 0, sinG = 0, gamma = 0;
};

// What the slices of one point share: N.V, and the camera's right and up against V and N.
struct SliceBasis {
    float nv, rv, uv, nr, nu;
};
SliceBasis sliceBasis(const Params& p, const Vec3f& N, const Vec3f& V) {
    return {dot(N, V), dot(p.right, V), dot(p.up, V), dot(N, p.right), dot(N, p.up)};
}

// In the orthonormal basis V, axis, V x axis of the slice, N's projection onto the slice plane is
// (N.V) V + (N.axis) axis, so its length (the slice's weight) and angle gamma need only N.V and
// N.axis: with screen = right dx + up dy (a unit vector) and s = screen.V, axis = (screen - s V) / L,
// L^2 = 1 - s^2, and N.axis = (N.screen - s N.V) / L. No cross product, no projected vector.
Slice sliceOf(const SliceBasis& sb, float dx, float dy) {
    Slice s;
    const float sv = dx * sb.rv + dy * sb.uv;
    const float axis2 = 1 - sv * sv;
    if (!(axis2 > 1e-12f)) return s;
    const float na = dx * sb.nr + dy * sb.nu - sb.nv * sv; // N.axis times L
    const float weight2 = sb.nv * sb.nv + na * na / axis2;
    s.weight = std::sqrt(weight2);
    if (!(s.weight > 1e-6f)) return s;
    s.cosG = sb.nv / s.weight, s.sinG = na / std::sqrt(axis2 * weight2);
    if (!(s.cosG > 0)) { // a normal turned away in this slice: taken as grazing
        s.cosG = 0;
        s.sinG = s.sinG >= 0 ? 1.0f : -1.0f;
    }
    s.gamma = s.sinG >= 0 ? fastAcos(s.cosG) : -fastAcos(s.cosG);
    s.valid = true;
    return s;
}

// The slice's visible part between its horizons (cosines of their angles from V; `raised` false: the
// tangent plane, gamma -+ pi/2), and with both at the tangent plane (open), through the same
// arithmetic so that a slice nothing occludes gives visible == open exactly.
void addSlice(const Slice& s, const float* horizon, const bool* raised, float& sum, float& sumOpen) {
    const float cosG = s.cosG, sinG = s.sinG;
    const float hMinus = s.gamma - 0.5f * kPi, hPlus = s.gamma + 0.5f * kPi;
    const float openMinus = arc(hMinus, sinG, -cosG, cosG, sinG);
    const float openPlus = arc(hPlus, -sinG, cosG, cosG, sinG);
    float a = 0;
    if (raised[0]) {
        const float c = horizon[0];
        a += arc(-fastAcos(c), c, -std::sqrt(std::max(0.0f, 1 - c * c)), cosG, sinG);
    } else {
        a += openMinus;
    }
    if (raised[1]) {
        const float c = horizon[1];
        a += arc(fastAcos(c), c, std::sqrt(std::max(0.0f, 1 - c * c)), cosG, sinG);
    } else {
        a += openPlus;
    }
    sum += s.weight * a;
    sumOpen += s.weight * (openMinus + openPlus);
}

// GTAO at point P with unit normal N over buffer `b`, the point at (cx, cy) in b's pixels (`here`:
// its own pixel, which the walk skips; -1: none), slices and offsets of pattern index k, in steps
// (so that two points can walk in one SIMD register, HorizonWalk8): per pair of slices s0, s0 + 1,
// `prepare` sets the four sides' lanes (slice s0's -axis and +axis sides, then slice s0 + 1's, or
// s0's again where there is none), a walk raises their horizons, `add` integrates the slices.
template <class Buffer> struct GtaoPoint {
    const Params& p;
    const std::array<float, kMaxDirections>& dirX;
    const std::array<float, kMaxDirections>& dirY;
    std::optional<HorizonWalk<Buffer>> walk; ///< empty: nothing occludes the point (1)
    SliceBasis basis{};
    float sum = 0, sumOpen = 0;
    Slice slice[2];
    int s0 = 0, s1 = 0;
    float sx[4] = {}, sy[4] = {}, horizon[4] = {};
    bool raised[4] = {};

    GtaoPoint(const Buffer& b, const Params& params, const Vec3f& P, const Vec3f& N, float cx, float cy,
              int64_t here, int k)
        : p(params), dirX(params.dirX[size_t(k)]), dirY(params.dirY[size_t(k)]) {
        const Vec3f toEye = p.eye - P;
        const float eyeDistance = length(toEye);
        const float depth = dot(P - p.eye, p.forward);
        if (!(eyeDistance > 0) || !(depth > 0)) return;
        const Vec3f V = toEye / eyeDistance;
        // The radius in working pixels at this depth; under a pixel nothing but p itself is in reach.
        const float radiusPixels = p.radius * p.pixelsPerTan / depth;
        if (!(radiusPixels >= 1)) return;
        basis = sliceBasis(p, N, V);
        const Vec3f rel = P - p.eye;
        walk.emplace(HorizonWalk<Buffer>{b,
                                         p,
                                         p.stepFraction[size_t(k)],
                                         here,
                                         cx,
                                         cy,
                                         kReach * radiusPixels,
                                         {dot(rel, p.right), dot(rel, p.up), depth},
                                         {basis.nr, basis.nu, dot(N, p.forward)},
                                         {basis.rv, basis.uv, dot(V, p.forward)}});
    }
    // False: both slices are degenerate (nothing to walk or add).
    bool prepare(int first) {
        s0 = first, s1 = std::min(first + 1, p.directions - 1);
        slice[0] = sliceOf(basis, dirX[size_t(s0)], dirY[size_t(s0)]);
        slice[1] = sliceOf(basis, dirX[size_t(s1)], dirY[size_t(s1)]);
        if (!slice[0].valid && !(s1 > s0 && slice[1].valid)) return false;
        for (int j = 0; j < 2; ++j) {
            const float dx = dirX[size_t(j ? s1 : s0)], dy = dirY[size_t(j ? s1 : s0)];
            sx[2 * j] = -dx, sy[2 * j] = -dy, sx[2 * j + 1] = dx, sy[2 * j + 1] = dy;
            horizon[2 * j] = slice[j].sinG, horizon[2 * j + 1] = -slice[j].sinG;
            raised[2 * j] = raised[2 * j + 1] = false;
        }
        return true;
    }
    void add() {
        if (slice[0].valid) addSlice(slice[0], horizon, raised, sum, sumOpen);
        if (s1 > s0 && slice[1].valid) addSlice(slice[1], horizon + 2, raised + 2, sum, sumOpen);
    }
    float result() const { return sumOpen > 0 ? std::clamp(sum / sumOpen, 0.0f, 1.0f) : 1.0f; }
    // The whole of it, one point.
    float run() {
        if (!walk) return 1;
        for (int first = 0; first < p.directions; first += 2)
            if (prepare(first)) {
                walkSides(*walk, p.scalarWalk, sx, sy, horizon, raised);
                add();
            }
        return result();
    }
};

template <class Buffer>
float occlusionOf(const Buffer& b, const Params& p, const Vec3f& P, const Vec3f& N, float cx, float cy,
                  int64_t here, int k) {
    return GtaoPoint<Buffer>(b, p, P, N, cx, cy, here, k).run();
}

// GTAO at working pixel (x, y): the visibility in [0, 1], 1 for background.
template <class Buffer> float occlusionAt(const Buffer& b, const Params& p, int64_t x, int64_t y) {
    const int64_t here = y * b.width + x;
    if (!b.covered(here) || b.skips(x, y, here)) return 1;
    return occlusionOf(b, p, b.position(here), b.normal(here), float(x) + 0.5f, float(y) + 0.5f, here,
                       kBayer[y & 3][x & 3]);
}

// Two points' GTAO (each prepared as GtaoPoint, with slices to walk): where both have a pair of
// slices to walk, in one AVX register (HorizonWalk8), else one at a time; each result as run() gives it.
template <class Buffer> void runPair(GtaoPoint<Buffer>& g0, GtaoPoint<Buffer>& g1) {
#if VOXFX_SSAO_AVX2
    for (int first = 0; first < g0.p.directions; first += 2) {
        const bool walk0 = g0.prepare(first), walk1 = g1.prepare(first);
        if (walk0 && walk1) {
            float sx[8], sy[8], horizon[8];
            for (int j = 0; j < 4; ++j) {
                sx[j] = g0.sx[j], sy[j] = g0.sy[j], horizon[j] = g0.horizon[j];
                sx[4 + j] = g1.sx[j], sy[4 + j] = g1.sy[j], horizon[4 + j] = g1.horizon[j];
            }
            const int bits = HorizonWalk8<Buffer>{*g0.walk, *g1.walk}.raise(sx, sy, horizon);
            for (int j = 0; j < 4; ++j) {
                g0.horizon[j] = horizon[j], g0.raised[j] = (bits >> j) & 1;
                g1.horizon[j] = horizon[4 + j], g1.raised[j] = (bits >> (4 + j)) & 1;
            }
        } else if (walk0) {
            walkSides(*g0.walk, false, g0.sx, g0.sy, g0.horizon, g0.raised);
        } else if (walk1) {
            walkSides(*g1.walk, false, g1.sx, g1.sy, g1.horizon, g1.raised);
        }
        if (walk0) g0.add();
        if (walk1) g1.add();
    }
#else
    g0.run(), g1.run();
#endif
}

// GTAO along row y of working buffer b into out (b.width values), as occlusionAt gives it: the pixels
// with something to walk two at a time (runPair), in row order, so that a row broken by background
// (the forest's leaves against the sky) still fills both halves of the register.
template <class Buffer> void occlusionRow(const Buffer& b, const Params& p, int64_t y, float* out) {
#if VOXFX_SSAO_AVX2
    const bool paired = !p.scalarWalk && b.width * b.height <= INT32_MAX;
#else
    const bool paired = false;
#endif
    std::optional<GtaoPoint<Buffer>> pending;
    int64_t pendingX = 0;
    for (int64_t x = 0; x < b.width; ++x) {
        const int64_t i = y * b.width + x;
        if (!b.covered(i) || !paired || b.skips(x, y, i)) {
            out[x] = occlusionAt(b, p, x, y);
            continue;
        }
        GtaoPoint<Buffer> g(b, p, b.position(i), b.normal(i), float(x) + 0.5f, float(y) + 0.5f, i,
                            kBayer[y & 3][x & 3]);
        if (!g.walk) {
            out[x] = 1; // as run() gives it
        } else if (!pending) {
            pending.emplace(g);
            pendingX = x;
        } else {
            runPair(*pending, g);
            out[pendingX] = pending->result(), out[x] = g.result();
            pending.reset();
        }
    }
    if (pending) out[pendingX] = pending->run();
}

// How much neighbour (q, m) belongs to the surface of p with unit normal n, in [0, tolerance]
// (tolerance at p itself; the weights around one p share the scale, which cancels): 0 beyond
// `tolerance` from p's tangent plane or with normals more than 90 degrees apart.
inline float similarity(const Vec3f& p, const Vec3f& n, float tolerance, const Vec3f& q, const Vec3f& m) {
    const float planeDistance = std::fabs(dot(q - p, n));
    const float c = dot(n, m);
    if (!(planeDistance < tolerance) || !(c > 0)) return 0;
    return (tolerance - planeDistance) * c * c;
}

// The blur's and the upsample's tolerance from p's tangent plane: a tenth of the radius (occlusion
// changes over the radius) plus two pixels' footprint at p's depth (what a smooth surface seen at a
// grazing angle curves away from its tangent plane over a pixel or two).
inline float planeTolerance(const Params& p, const Vec3f& position) {
    const float depth = std::max(dot(position - p.eye, p.forward), 0.0f);
    return 0.1f * p.radius + 2 * depth * p.pixelSize;
}

// Per working pixel: kUniform (the upsample's fast path: its block's samples are one smooth surface
// and it is their mean), kLinkRight and kLinkUp (it and its neighbour at x + 1, y + 1 lie on one
// smooth surface: each within the tolerance of the other's tangent plane, normals within 25 deg).
constexpr uint8_t kUniform = 1, kLinkRight = 2, kLinkUp = 4;
constexpr float kLinkCos = 0.9f;

void linkNeighbours(const Packed& b, const Params& p, std::vector<uint8_t>& links) {
    const int64_t W = b.width, H = b.height;
    const auto linked = [&](int64_t i, int64_t j, float toleranceI) {
        if (!b.covered(j)) return false;
        const Vec3f &P = b.position(i), &N = b.normal(i), &Q = b.position(j), &M = b.normal(j);
        return std::fabs(dot(Q - P, N)) < toleranceI && std::fabs(dot(P - Q, M)) < planeTolerance(p, Q) &&
               dot(N, M) > kLinkCos;
    };
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const int64_t i = y * W + x;
                uint8_t l = links[size_t(i)] & kUniform;
                if (b.covered(i)) {
                    const float tolerance = planeTolerance(p, b.position(i));
                    if (x + 1 < W && linked(i, i + 1, tolerance)) l |= kLinkRight;
                    if (y + 1 < H && linked(i, i + W, tolerance)) l |= kLinkUp;
                }
                links[size_t(i)] = l;
            }
    });
}

// A walk sample's offset from its pixel's central ray (tangent units) in units of `quant`, clamped
// to int16 (a point more than 4 pixels off its pixel's ray, which no buffer of this file holds).
int16_t offsetUnits(float offset, float quant) {
    const float u = std::round(offset / quant);
    return int16_t(u > 32767 ? 32767.0f : u >= -32767 ? u : -32767.0f);
}

// The horizon search's copy of working buffer b (Packed::walk): per pixel that occludes, its depth and
// offsets in view space.
void walkSamples(Packed& b, const Params& p, std::vector<ScreenSpaceWalkSample>& out) {
    out.resize(std::size_t(b.width * b.height));
    parallelFor(0, b.height, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < b.width; ++x) {
                const int64_t i = y * b.width + x;
                ScreenSpaceWalkSample w;
                const Vec3f rel = b.position(i) - p.eye;
                const float z = dot(rel, p.forward);
                if (b.occludes(i) && z > 0) {
                    w.depth = z;
                    w.offsetX =
                        offsetUnits(dot(rel, p.right) / z - (p.txBase + float(x) * p.txStep), p.txQuant);
                    w.offsetY = offsetUnits(dot(rel, p.up) / z - (p.tyBase + float(y) * p.tyStep), p.tyQuant);
                }
                out[std::size_t(i)] = w;
            }
    });
    b.walk = out.data();
}

// Where the horizon search may be skipped (ScreenSpaceOcclusionOptions::flatMeshes), per 8x8 tile of
// working buffer b (walk copy made, scratch.meshes filled): the tile's occluders' depth range and mesh;
// then per tile, over the tiles its pixels' search can reach (its pixels' extent grown by the reach
// at its nearest pixel, plus one pixel for the truncation of the sample positions), whether every
// occluder there lies at least 2 radii from its pixels in view depth (skipAll), or from its pixels
// of one flat mesh, that mesh's own occluders excepted (skipMesh). A walk raises a horizon only by an
// occluder within the radius, or by the crossing of the sphere between one within the radius and
// the next sample, which lies within twice the radius; points of a flat mesh rise above a tangent
// plane of it by rounding only, far below the bias angle. So a skipped pixel's search would have
// found nothing, and its visibility is 1 exactly as the search gives it (the open slices' sums are
// the visible ones, term for term). Windows wider than kMaxWindowTiles tiles are not checked.
constexpr int64_t kTile = 8, kMaxWindowTiles = 24;
void skipTiles(Packed& b, const Params& p, std::span<const uint8_t> flatMeshes,
               ScreenSpaceOcclusionScratch& scratch) {
    using Tile = ScreenSpaceOcclusionScratch::Tile;
    const int64_t W = b.width, H = b.height, tw = (W + kTile - 1) / kTile, th = (H + kTile - 1) / kTile;
    std::vector<Tile>& tiles = scratch.tiles;
    tiles.assign(std::size_t(tw * th), Tile{});
    const int32_t* mesh = scratch.meshes.data();
    const auto isFlat = [&](int32_t m) {
        return m >= 0 && std::size_t(m) < flatMeshes.size() && flatMeshes[size_t(m)];
    };
    // The tiles' occluders.
    parallelFor(0, th, 4, [&](int64_t t0, int64_t t1) {
        for (int64_t ty = t0; ty < t1; ++ty)
            for (int64_t tx = 0; tx < tw; ++tx) {
                Tile& t = tiles[std::size_t(ty * tw + tx)];
                for (int64_t y = ty * kTile; y < std::min(H, (ty + 1) * kTile); ++y)
                    for (int64_t x = tx * kTile; x < std::min(W, (tx + 1) * kTile); ++x) {
                        const int64_t i = y * W + x;
                        const float z = b.walk[i].depth;
                        if (!(z > 0)) continue;
                        if (t.occluderMesh == -1) {
                            t.occluderMin = t.occluderMax = z;
                            t.occluderMesh = mesh[i] >= 0 ? mesh[i] : -2;
                        } else {
                            t.occluderMin = std::min(t.occluderMin, z),
                            t.occluderMax = std::max(t.occluderMax, z);
                            if (t.occluderMesh != mesh[i]) t.occluderMesh = -2;
                        }
                    }
            }
    });
    const float twoRadii = 2 * p.radius;
    // The verdicts (each tile reads the others' occluders only).
    parallelFor(0, th, 4, [&](int64_t t0, int64_t t1) {
        for (int64_t ty = t0; ty < t1; ++ty)
            for (int64_t tx = 0; tx < tw; ++tx) {
                // The tile's pixels: their depth range, and that of its first flat mesh's.
                float allMin = 0, allMax = 0, flatMin = 0, flatMax = 0;
                bool any = false, anyFlat = false;
                int32_t flat = -1;
                const int64_t x0 = tx * kTile, x1 = std::min(W, x0 + kTile), y0 = ty * kTile,
                              y1 = std::min(H, y0 + kTile);
                for (int64_t y = y0; y < y1; ++y)
                    for (int64_t x = x0; x < x1; ++x) {
                        const int64_t i = y * W + x;
                        if (!b.covered(i)) continue;
                        const float z = dot(b.position(i) - p.eye, p.forward);
                        allMin = any ? std::min(allMin, z) : z, allMax = any ? std::max(allMax, z) : z;
                        any = true;
                        if (flat < 0 && isFlat(mesh[i])) flat = mesh[i];
                        if (flat >= 0 && mesh[i] == flat) {
                            flatMin = anyFlat ? std::min(flatMin, z) : z;
                            flatMax = anyFlat ? std::max(flatMax, z) : z;
                            anyFlat = true;
                        }
                    }
                if (!any || !(allMin > 0)) continue;
                // Each group's verdict over the tiles in reach of its nearest pixel.
                const auto clear = [&](float zMin, float zMax, int32_t own) {
                    const float reach = 1.01f * kReach * p.radius * p.pixelsPerTan / zMin + 2;
                    if (!(reach < float(kMaxWindowTiles * kTile))) return false;
                    const auto r = int64_t(std::ceil(reach));
                    const int64_t ux0 = std::max<int64_t>(0, (x0 - r) / kTile),
                                  ux1 = std::min(tw - 1, (x1 - 1 + r) / kTile),
                                  uy0 = std::max<int64_t>(0, (y0 - r) / kTile),
                                  uy1 = std::min(th - 1, (y1 - 1 + r) / kTile);
                    for (int64_t uy = uy0; uy <= uy1; ++uy)
                        for (int64_t ux = ux0; ux <= ux1; ++ux) {
                            const Tile& u = tiles[std::size_t(uy * tw + ux)];
                            if (u.occluderMesh == -1 || (own >= 0 && u.occluderMesh == own)) continue;
                            if (u.occluderMax < zMin - twoRadii || u.occluderMin > zMax + twoRadii) continue;
                            return false;
                        }
                    return true;
                };
                Tile& t = tiles[std::size_t(ty * tw + tx)];
                t.skipAll = clear(allMin, allMax, -1);
                if (!t.skipAll && anyFlat && flatMin > 0 && clear(flatMin, flatMax, flat)) t.skipMesh = flat;
            }
    });
    b.mesh = mesh;
    b.tiles = tiles.data();
    b.tileColumns = tw;
}

// Step 3: the separable blur, weights 1 2 2 2 1 over the pixels linked to the centre through a chain
// of links (a binary bilateral filter: nothing crosses an edge or a crease), along x then y.
void blur(const Packed& b, const std::vector<uint8_t>& links, std::span<const float> raw,
          std::span<float> across, std::span<float> out) {
    const int64_t W = b.width, H = b.height;
    const auto pass = [&](std::span<const float> in, std::span<float> result, int64_t stride, uint8_t link) {
        parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
            for (auto i = std::size_t(y0 * W); i < std::size_t(y1 * W); ++i) {
                if (!b.covered(int64_t(i))) {
                    result[i] = 1;
                    continue;
                }
                // Links are 0 at the image's sides, so no index leaves it.
                float sum = 2 * in[i], weights = 2;
                if (links[i] & link) {
                    sum += 2 * in[i + size_t(stride)], weights += 2;
                    if (links[i + size_t(stride)] & link) sum += in[i + size_t(2 * stride)], weights += 1;
                }
                if (i >= size_t(stride) && (links[i - size_t(stride)] & link)) {
                    sum += 2 * in[i - size_t(stride)], weights += 2;
                    if (i >= size_t(2 * stride) && (links[i - size_t(2 * stride)] & link))
                        sum += in[i - size_t(2 * stride)], weights += 1;
                }
                result[i] = sum / weights;
            }
        });
    };
    pass(raw, across, 1, kLinkRight);
    pass(across, out, W, kLinkUp);
}

void checkOptions(const ScreenSpaceOcclusionOptions& options) {
    if (!(options.radius > 0 && std::isfinite(options.radius)))
        fail("screen-space ambient occlusion: the radius must be positive and finite, got ", options.radius);
    if (options.directions < 1 || options.directions > kMaxDirections)
        fail("screen-space ambient occlusion: directions must be between 1 and ", kMaxDirections, ", got ",
             options.directions);
    if (options.steps < 1 || options.steps > kMaxSteps)
        fail("screen-space ambient occlusion: steps must be between 1 and ", kMaxSteps, ", got ",
             options.steps);
    if (!(options.bias >= 0 && options.bias <= M_PI / 4))
        fail("screen-space ambient occlusion: the bias must lie in [0, pi/4] radians, got ", options.bias);
}

void checkArguments(const Frame& camera, int64_t width, int64_t height, std::span<const Vec3f> position,
                    std::span<const Vec3f> normal, std::span<const uint8_t> covered,
                    const ScreenSpaceOcclusionOptions& options, std::span<const uint8_t> occluder,
                    std::span<float> visibility) {
    if (!camera.isPerspective()) fail("screen-space ambient occlusion: the camera frame must be perspective");
    if (width <= 0 || height <= 0 || camera.width() != width || camera.height() != height)
        fail("screen-space ambient occlusion: the buffer is ", width, " x ", height,
             " samples but the camera's is ", camera.width(), " x ", camera.height());
    const auto count = std::size_t(width * height);
    if (position.size() != count || normal.size() != count || covered.size() != count ||
        (!occluder.empty() && occluder.size() != count) || visibility.size() != count)
        fail("screen-space ambient occlusion: ", count, " samples, but ", position.size(), " positions, ",
             normal.size(), " normals, ", covered.size(), " coverage flags, ", occluder.size(),
             " occluder flags and room for ", visibility.size(), " results");
    checkOptions(options);
}

// Without halfResolution: GTAO at every sample, linked and blurred.
template <class Source>
void fullResolution(const Source& full, const Params& fullParams, std::span<float> visibility,
                    ScreenSpaceOcclusionScratch& scratch) {
    const int64_t W = full.width, H = full.height;
    const auto count = std::size_t(W * H);
    std::vector<Sample>& samples = scratch.samples;
    std::vector<Vec3f>& normals = scratch.normals;
    samples.resize(count);
    normals.resize(count);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = std::size_t(y * W + x);
                if (!full.covered(x, y)) {
                    samples[i] = {};
                    normals[i] = {};
                    continue;
                }
                samples[i] = {full.position(x, y), kCovered | (full.occludes(x, y) ? kOccluder : 0u)};
                normals[i] = full.normal(x, y);
            }
    });
    Packed packed{W, H, samples.data(), normals.data()};
    walkSamples(packed, fullParams, scratch.walk);
    scratch.raw.resize(count);
    parallelFor(0, H, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y) occlusionRow(packed, fullParams, y, &scratch.raw[size_t(y * W)]);
    });
    scratch.links.assign(count, 0);
    linkNeighbours(packed, fullParams, scratch.links);
    scratch.across.resize(count);
    blur(packed, scratch.links, scratch.raw, scratch.across, visibility);
}

// A covered sample of a 2x2 block, as the downsample reads it.
struct BlockSample {
    int64_t x, y;
    Vec3f position;
};
// Whether the four samples of a block show one triangle (the G-buffer's cells: then they are one
// surface without testing their normals); the caller's buffers do not say.
bool oneTriangle(const Spans&, const BlockSample*) { return false; }
bool oneTriangle(const Cells& cells, const BlockSample* block) {
    const uint32_t t = cells.triangle(block[0].x, block[0].y);
    for (int k = 1; k < 4; ++k)
        if (cells.triangle(block[k].x, block[k].y) != t) return false;
    return true;
}

// Step 1, the working buffer at half resolution (in scratch: samples, normals, and links, where
// kUniform marks a block of one smooth surface).
template <class Source>
Packed downsample(const Source& full, const Params& fullParams, const Frame& camera,
                  ScreenSpaceOcclusionScratch& scratch, bool meshes) {
    const int64_t W = full.width, H = full.height;
    // Step 1: per 2x2 block, the mean of its samples where they all show one smooth surface (then
    // the working pixel sits at the block's centre, where the upsample expects it), else the covered
    // sample nearest the eye (ties: the first in row order), so that a thin object in front keeps it.
    const int64_t w = (W + 1) / 2, h = (H + 1) / 2;
    const auto lowCount = std::size_t(w * h);
    std::vector<Sample>& lowSample = scratch.samples;
    std::vector<Vec3f>& lowNormal = scratch.normals;
    std::vector<uint8_t>& links = scratch.links;
    lowSample.resize(lowCount);
    lowNormal.resize(lowCount);
    links.resize(lowCount);
    // With `meshes`, per working pixel the mesh its point lies on (skipTiles): its sample's, or for a
    // block's mean, the one mesh of all its samples (-1 where they show several).
    std::vector<int32_t>& lowMesh = scratch.meshes;
    if (meshes) lowMesh.resize(lowCount);
    const Vec3f eye(camera.eye()), forward(camera.forward());
    parallelFor(0, h, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < w; ++x) {
                BlockSample block[4];
                int n = 0, best = -1, inside = 0;
                float bestDepth = 0;
                for (int64_t j = 2 * y; j < std::min(H, 2 * y + 2); ++j)
                    for (int64_t i = 2 * x; i < std::min(W, 2 * x + 2); ++i) {
                        ++inside;
                        if (!full.covered(i, j)) continue;
                        block[n] = {i, j, full.position(i, j)};
                        const float d = dot(block[n].position - eye, forward);
                        if (best < 0 || d < bestDepth) best = n, bestDepth = d;
                        ++n;
                    }
                const auto l = std::size_t(y * w + x);
                links[l] = 0;
                if (best < 0) {
                    lowSample[l] = {};
                    lowNormal[l] = {};
                    if (meshes) lowMesh[l] = -1;
                    continue;
                }
                const BlockSample& b = block[best];
                const Vec3f P = b.position;
                const bool occludes = full.occludes(b.x, b.y);
                bool uniform = n == 4;
                Vec3f sumPosition{0, 0, 0}, sumNormal{0, 0, 0};
                if (uniform && oneTriangle(full, block)) { // one plane, one material
                    for (const BlockSample& c : block) sumPosition += c.position;
                } else if (uniform) {
                    // One smooth surface: all occluders or none, within a sample's footprint of the
                    // nearest sample's tangent plane, normals within about 18 degrees of its normal
                    // (a sample's normal read only where the other two tests pass: a block that
                    // fails is not a mean, and its sums go unused).
                    const Vec3f N = full.testNormal(b.x, b.y, P);
                    const float footprint = bestDepth * fullParams.pixelSize;
                    for (int k = 0; k < n && uniform; ++k) {
                        const BlockSample& c = block[k];
                        uniform = full.occludes(c.x, c.y) == occludes &&
                                  std::fabs(dot(c.position - P, N)) <= footprint;
                        if (!uniform) break;
                        const Vec3f m = k == best ? N : full.testNormal(c.x, c.y, c.position);
                        uniform = dot(m, N) >= 0.95f;
                        sumPosition += c.position;
                        sumNormal += m;
                    }
                }
                lowSample[l].flags = kCovered | (occludes ? kOccluder : 0u);
                const Vec3f mean = sumPosition * 0.25f;
                const Vec3f meanNormal =
                    uniform && inside == 4 ? full.meanNormal(sumNormal, b.x, b.y, mean) : Vec3f{0, 0, 0};
                const bool isMean = length(meanNormal) > 0;
                if (isMean) {
                    lowSample[l].position = mean;
                    lowNormal[l] = meanNormal;
                    links[l] = kUniform;
                } else {
                    lowSample[l].position = P;
                    lowNormal[l] = full.normalAt(b.x, b.y, P);
                }
                if (meshes) {
                    int32_t m = full.meshOf(b.x, b.y);
                    if (isMean)
                        for (int k = 0; k < n; ++k)
                            if (full.meshOf(block[k].x, block[k].y) != m) m = -1;
                    lowMesh[l] = m;
                }
            }
    });
    return Packed{w, h, lowSample.data(), lowNormal.data()};
}

// Step 4, back to full resolution, one sample at a time: the blurred working pixels (`smooth`) of
// `low`, with the links the blur followed. Working pixel (a, b) is centred on sample (2a + 1, 2b + 1),
// so sample (x, y) lies between working pixels a0 = floor((x - 1) / 2) and a0 + 1 at 3/4 and 1/4
// (x even) or 1/4 and 3/4 (x odd), and likewise in y. Where its own block is uniform and the four
// are linked, it takes their bilinear mean (bilinear: no need of its surface); elsewhere the four
// weighted by their similarity to its own surface too; where none is similar, the most similar of the
// 4x4 around it; where none is at all (a sliver no block kept), GTAO at the sample itself over the
// working buffer (weighted).
struct Upsample {
    Packed low;
    const uint8_t* links = nullptr;
    const float* smooth = nullptr;
    Params lowParams; ///< the working buffer's

    bool bilinear(int64_t x, int64_t y, float& out) const {
        const int64_t w = low.width, h = low.height;
        const int64_t a0 = (x - 1) >> 1, b0 = (y - 1) >> 1; // arithmetic shift: floor
        if (!(a0 >= 0 && b0 >= 0 && a0 + 1 < w && b0 + 1 < h)) return false;
        const auto l = std::size_t(b0 * w + a0), up = l + std::size_t(w);
        if (!((links[std::size_t((y >> 1) * w + (x >> 1))] & kUniform) &&
              (links[l] & (kLinkRight | kLinkUp)) == (kLinkRight | kLinkUp) && (links[l + 1] & kLinkUp) &&
              (links[up] & kLinkRight)))
            return false;
        const float fx = (x & 1) ? 0.25f : 0.75f, fy = (y & 1) ? 0.25f : 0.75f;
        out = (1 - fy) * ((1 - fx) * smooth[l] + fx * smooth[l + 1]) +
              fy * ((1 - fx) * smooth[up] + fx * smooth[up + 1]);
        return true;
    }

    // Sample (x, y) at P with unit normal N (the source's upsampleNormal) off the bilinear path.
    template <class Source>
    float weighted(const Source& full, const Params& fullParams, int64_t x, int64_t y, const Vec3f& P,
                   const Vec3f& N) const {
        const int64_t w = low.width, h = low.height;
        const int64_t a0 = (x - 1) >> 1, b0 = (y - 1) >> 1;
        const float fx = (x & 1) ? 0.25f : 0.75f, fy = (y & 1) ? 0.25f : 0.75f;
        const float tolerance = planeTolerance(fullParams, P);
        float sum = 0, weights = 0;
        for (int db = 0; db < 2; ++db)
            for (int da = 0; da < 2; ++da) {
                const int64_t a = a0 + da, bb = b0 + db;
                if (a < 0 || bb < 0 || a >= w || bb >= h) continue;
                const auto l = std::size_t(bb * w + a);
                if (!low.covered(int64_t(l))) continue;
                const float wgt = (da ? fx : 1 - fx) * (db ? fy : 1 - fy) *
                                  similarity(P, N, tolerance, low.sample[l].position, low.normals[l]);
                sum += wgt * smooth[l];
                weights += wgt;
            }
        if (weights > 1e-3f * tolerance) return sum / weights;
        float best = 0, out = 1;
        for (int64_t bb = std::max<int64_t>(0, b0 - 1); bb <= std::min(h - 1, b0 + 2); ++bb)
            for (int64_t a = std::max<int64_t>(0, a0 - 1); a <= std::min(w - 1, a0 + 2); ++a) {
                const auto l = std::size_t(bb * w + a);
                if (!low.covered(int64_t(l))) continue;
                const float s = similarity(P, N, tolerance, low.sample[l].position, low.normals[l]);
                if (s > best) best = s, out = smooth[l];
            }
        // The sliver's own GTAO, walking the working buffer (as every working pixel's does) from its
        // point at its place on it: the full-resolution buffer is not there to walk in the G-buffer's
        // case (reading it costs a triangle and a material per step), and the working buffer holds
        // the occluders around at the resolution the others see them.
        if (best > 0) return out;
        return occlusionOf(low, lowParams, P, full.normal(x, y), 0.5f * (float(x) + 0.5f),
                           0.5f * (float(y) + 0.5f), -1, kBayer[y & 3][x & 3]);
    }
};

// Step 4 over every sample of `full` into `out`.
template <class Source>
void upsample(const Source& full, const Params& fullParams, const Upsample& up, std::span<float> out) {
    parallelFor(0, full.height, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < full.width; ++x) {
                float& v = out[size_t(y * full.width + x)];
                if (!full.covered(x, y))
                    v = 1;
                else if (!up.bilinear(x, y, v))
                    v = up.weighted(full, fullParams, x, y, full.position(x, y), full.upsampleNormal(x, y));
            }
    });
}

// Steps 1-3 at half resolution over `full` (at camera's resolution times `scale` samples per side):
// what the upsample reads, in `scratch`.
template <class Source>
Upsample workingOcclusion(const Source& full, const Params& fullParams, const Frame& camera, int scale,
                          const ScreenSpaceOcclusionOptions& options, ScreenSpaceOcclusionScratch& scratch) {
    const bool skipping = !options.flatMeshes.empty() && Source::kMeshes;
    Packed low = downsample(full, fullParams, camera, scratch, skipping);
    const int64_t w = low.width, h = low.height;
    const auto lowCount = std::size_t(w * h);
    std::vector<uint8_t>& links = scratch.links;
    const Params p = makeParams(camera, 2 * scale, options);
    walkSamples(low, p, scratch.walk);
    if (skipping) skipTiles(low, p, options.flatMeshes, scratch);
    scratch.raw.resize(lowCount);
    parallelFor(0, h, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y) occlusionRow(low, p, y, &scratch.raw[size_t(y * w)]);
    });
    linkNeighbours(low, p, links);
    scratch.across.resize(lowCount);
    scratch.smooth.resize(lowCount);
    blur(low, links, scratch.raw, scratch.across, scratch.smooth);
    return Upsample{low, links.data(), scratch.smooth.data(), p};
}

// GTAO over `full` (at camera's resolution times `scale` samples per side) into `visibility`.
template <class Source>
void occlusionOf(const Source& full, const Frame& camera, int scale,
                 const ScreenSpaceOcclusionOptions& options, std::span<float> visibility,
                 ScreenSpaceOcclusionScratch& scratch) {
    const Params fullParams = makeParams(camera, scale, options);
    if (!options.halfResolution) {
        fullResolution(full, fullParams, visibility, scratch);
        return;
    }
    upsample(full, fullParams, workingOcclusion(full, fullParams, camera, scale, options, scratch),
             visibility);
}

} // namespace

void screenSpaceOcclusion(const Frame& camera, int64_t width, int64_t height, std::span<const Vec3f> position,
                          std::span<const Vec3f> normal, std::span<const uint8_t> covered,
                          const ScreenSpaceOcclusionOptions& options, std::span<const uint8_t> occluder,
                          std::span<float> visibility, ScreenSpaceOcclusionScratch& scratch) {
    checkArguments(camera, width, height, position, normal, covered, options, occluder, visibility);
    const Spans full{width,         height,         position.data(),
                     normal.data(), covered.data(), occluder.empty() ? nullptr : occluder.data()};
    occlusionOf(full, camera, 1, options, visibility, scratch);
}

namespace {

void checkCells(const GBuffer& gbuffer, const SceneGeometry& geometry, std::span<const TriangleBasis> bases,
                int adaptive, std::span<const TriangleTag> tags) {
    const Frame& camera = gbuffer.frame;
    if (!camera.isPerspective()) fail("screen-space ambient occlusion: the camera frame must be perspective");
    if (adaptive < 1 || camera.width() % adaptive || camera.height() % adaptive)
        fail("screen-space ambient occlusion: the G-buffer's ", camera.width(), " x ", camera.height(),
             " samples are not cells of ", adaptive, " x ", adaptive);
    if (bases.size() != geometry.mesh.triangleCount())
        fail("screen-space ambient occlusion: ", bases.size(), " triangle bases for ",
             geometry.mesh.triangleCount(), " triangles");
    if (!tags.empty() && tags.size() != bases.size())
        fail("screen-space ambient occlusion: ", tags.size(), " triangle tags for ", bases.size(),
             " triangles");
    if (camera.width() / adaptive <= 0 || camera.height() / adaptive <= 0)
        fail("screen-space ambient occlusion: the G-buffer has no cells");
}

} // namespace

void screenSpaceOcclusion(const GBuffer& gbuffer, const SceneGeometry& geometry,
                          std::span<const TriangleBasis> bases, std::span<const uint8_t> opaqueMaterial,
                          int adaptive, const ScreenSpaceOcclusionOptions& options,
                          std::span<float> visibility, ScreenSpaceOcclusionScratch& scratch,
                          std::span<const TriangleTag> tags) {
    checkCells(gbuffer, geometry, bases, adaptive, tags);
    const Cells full(gbuffer, geometry, bases, opaqueMaterial, adaptive, tags);
    if (visibility.size() != std::size_t(full.width * full.height))
        fail("screen-space ambient occlusion: ", full.width * full.height, " cells but room for ",
             visibility.size(), " results");
    checkOptions(options);
    occlusionOf(full, gbuffer.frame, adaptive, options, visibility, scratch);
}

struct CellOcclusion::Impl {
    int64_t width = 0, height = 0;
    virtual ~Impl() = default;
    virtual float at(int64_t cx, int64_t cy, const Vec3f& position, const Vec3f& faceNormal) const = 0;
};

namespace {

// CellOcclusion's state (the source's types live in this file's anonymous namespace).
struct CellOcclusionState final : CellOcclusion::Impl {
    Cells full;
    Params fullParams;
    Upsample up;
    std::vector<float> cells; ///< without halfResolution: every cell's visibility
    CellOcclusionState(const GBuffer& gbuffer, const SceneGeometry& geometry,
                       std::span<const TriangleBasis> bases, std::span<const uint8_t> opaqueMaterial,
                       int adaptive, const ScreenSpaceOcclusionOptions& options,
                       ScreenSpaceOcclusionScratch& scratch, std::span<const TriangleTag> tags)
        : full(gbuffer, geometry, bases, opaqueMaterial, adaptive, tags),
          fullParams(makeParams(gbuffer.frame, adaptive, options)) {
        width = full.width;
        height = full.height;
        if (options.halfResolution) {
            up = workingOcclusion(full, fullParams, gbuffer.frame, adaptive, options, scratch);
            return;
        }
        cells.resize(std::size_t(full.width * full.height));
        fullResolution(full, fullParams, cells, scratch);
    }
    float at(int64_t cx, int64_t cy, const Vec3f& position, const Vec3f& faceNormal) const override {
        if (!cells.empty()) return cells[std::size_t(cy * full.width + cx)];
        float v = 1;
        if (!up.bilinear(cx, cy, v)) v = up.weighted(full, fullParams, cx, cy, position, faceNormal);
        return v;
    }
};

} // namespace

CellOcclusion::CellOcclusion(const GBuffer& gbuffer, const SceneGeometry& geometry,
                             std::span<const TriangleBasis> bases, std::span<const uint8_t> opaqueMaterial,
                             int adaptive, const ScreenSpaceOcclusionOptions& options,
                             ScreenSpaceOcclusionScratch& scratch, std::span<const TriangleTag> tags) {
    checkCells(gbuffer, geometry, bases, adaptive, tags);
    checkOptions(options);
    impl_ = std::make_unique<CellOcclusionState>(gbuffer, geometry, bases, opaqueMaterial, adaptive, options,
                                                 scratch, tags);
}

CellOcclusion::~CellOcclusion() = default;

int64_t CellOcclusion::width() const { return impl_->width; }
int64_t CellOcclusion::height() const { return impl_->height; }

float CellOcclusion::at(int64_t cx, int64_t cy, const Vec3f& position, const Vec3f& faceNormal) const {
    return impl_->at(cx, cy, position, faceNormal);
}

std::vector<float> screenSpaceOcclusion(const Frame& camera, int64_t width, int64_t height,
                                        std::span<const Vec3f> position, std::span<const Vec3f> normal,
                                        std::span<const uint8_t> covered,
                                        const ScreenSpaceOcclusionOptions& options,
                                        std::span<const uint8_t> occluder) {
    std::vector<float> visibility(std::size_t(std::max<int64_t>(width, 0) * std::max<int64_t>(height, 0)));
    ScreenSpaceOcclusionScratch scratch;
    screenSpaceOcclusion(camera, width, height, position, normal, covered, options, occluder, visibility,
                         scratch);
    return visibility;
}

SurfaceBuffers gatherSurfaces(const GBuffer& gbuffer, const SceneGeometry& geometry,
                              std::span<const Material> materials) {
    const int64_t W = gbuffer.frame.width(), H = gbuffer.frame.height();
    const auto count = std::size_t(W * H);
    SurfaceBuffers s;
    s.position.assign(count, Vec3f{0, 0, 0});
    s.normal.assign(count, Vec3f{0, 0, 0});
    s.covered.assign(count, 0);
    s.occluder.assign(count, 0);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        SurfacePoint sp;
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                if (!surfaceAt(gbuffer, geometry, x, y, sp)) continue;
                const auto i = std::size_t(y * W + x);
                s.position[i] = Vec3f(sp.position);
                s.normal[i] = Vec3f(sp.normal);
                s.covered[i] = 1;
                s.occluder[i] = sp.material < materials.size() && materials[sp.material].isOpaque();
            }
    });
    return s;
}

FieldOcclusionSetup fieldOcclusionSetup(const SceneGeometry& g, std::span<const Material> materials,
                                        std::size_t meshCount, double radius, int64_t resolution) {
    FieldOcclusionSetup out;
    const Mesh& mesh = g.mesh;
    // Opaque triangles occlude; per mesh, its bounds and whether it is flat (every vertex on the
    // plane of its largest triangle, to 1e-6 of its size).
    struct PerMesh {
        Box3d box;
        Vec3d normal, point;
        double area2 = 0;
        bool flat = true;
    };
    // Triangle t into its mesh's box and largest triangle.
    auto addTriangle = [&](PerMesh& m, std::size_t t) {
        const Vec3d a = Vec3d(mesh.positions[mesh.indices[3 * t]]),
                    b = Vec3d(mesh.positions[mesh.indices[3 * t + 1]]),
                    c = Vec3d(mesh.positions[mesh.indices[3 * t + 2]]);
        m.box.extend(a), m.box.extend(b), m.box.extend(c);
        const Vec3d n = cross(b - a, c - a);
        if (dot(n, n) > m.area2) m.area2 = dot(n, n), m.normal = n, m.point = a;
    };
    // Triangle t's corners on the plane of its mesh's largest triangle, to 1e-6 of the mesh's size,
    // or the mesh is not flat.
    auto checkFlat = [&](PerMesh& m, std::size_t t) {
        if (!m.flat || m.area2 <= 0) return;
        const double tol = 1e-6 * length(m.box.extent());
        const Vec3d n = m.normal / std::sqrt(m.area2);
        for (int k = 0; k < 3; ++k)
            if (std::fabs(dot(Vec3d(mesh.positions[mesh.indices[3 * t + k]]) - m.point, n)) > tol)
                m.flat = false;
    };
    std::vector<PerMesh> meshes(meshCount);
    std::vector<std::size_t> opaque;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t mat = g.triangleMaterial[t];
        if (mat >= materials.size() || !materials[mat].isOpaque() || g.triangleMesh[t] >= meshCount) continue;
        opaque.push_back(t);
        addTriangle(meshes[g.triangleMesh[t]], t);
    }
    // Per mesh, flat over all its triangles (any material): every vertex on the plane of its largest
    // triangle, to 1e-6 of its size.
    {
        std::vector<PerMesh> all(meshCount);
        for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
            if (g.triangleMesh[t] < meshCount) addTriangle(all[g.triangleMesh[t]], t);
        for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
            if (g.triangleMesh[t] < meshCount) checkFlat(all[g.triangleMesh[t]], t);
        out.flatMeshes.resize(meshCount);
        for (std::size_t i = 0; i < meshCount; ++i) out.flatMeshes[i] = all[i].flat && all[i].area2 > 0;
    }
    if (opaque.empty()) return out;
    for (const std::size_t t : opaque) checkFlat(meshes[g.triangleMesh[t]], t);
    out.indices.reserve(3 * opaque.size());
    for (const std::size_t t : opaque)
        for (int k = 0; k < 3; ++k) out.indices.push_back(mesh.indices[3 * t + k]);
    std::vector<double> diagonals;
    for (int pass = 0; pass < 2 && out.region.empty(); ++pass)
        for (const PerMesh& m : meshes)
            if (!m.box.empty() && (pass == 1 || !m.flat)) {
                out.region.extend(m.box.lo), out.region.extend(m.box.hi);
                diagonals.push_back(length(m.box.extent()));
            }
    std::sort(diagonals.begin(), diagonals.end());
    out.radius = radius > 0 ? radius : 0.1 * diagonals[diagonals.size() / 2];
    if (!(out.radius > 0)) {
        out.radius = 0;
        return out;
    }
    const Vec3d extent = out.region.extent() + Vec3d{2, 2, 2} * out.radius;
    const double longest = std::max({extent.x, extent.y, extent.z});
    out.resolution = std::clamp<int64_t>(
        std::max<int64_t>(resolution, int64_t(std::ceil(4 * longest / out.radius))), 8, 2048);
    return out;
}

} // namespace voxfx::detail
