// voxfx — adaptive sample selection, FXAA-style post-process and the filmic curve (antialias.hpp).
#include "render/antialias.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>

#ifdef __AVX2__
#include <immintrin.h>
#endif

#include "render/render_cache.hpp"
#include "render/vec_simd.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx {

const char* toString(AntiAliasing a) { return enumName(a, kAntiAliasingNames); }
AntiAliasing parseAntiAliasing(const std::string& name) {
    return parseEnum<AntiAliasing>(name, "anti-aliasing", kAntiAliasingNames);
}
const char* toString(ToneMap t) { return enumName(t, kToneMapNames); }
ToneMap parseToneMap(const std::string& name) { return parseEnum<ToneMap>(name, "tone map", kToneMapNames); }
ToneMap toneMapForImage(ToneMap requested, std::string_view path) {
    if (requested != ToneMap::Auto) return requested;
    const std::string ext = fileExtension(std::filesystem::path(path));
    return ext == ".exr" || ext == ".pfm" || ext == ".hdr" ? ToneMap::Clamp : ToneMap::Filmic;
}
const char* toString(SkyKind k) { return enumName(k, kSkyKindNames); }
SkyKind parseSkyKind(const std::string& name) { return parseEnum<SkyKind>(name, "sky", kSkyKindNames); }

float filmicToneMap(float x) {
    if (!(x > 0)) return 0;
    // Narkowicz 2015, "ACES Filmic Tone Mapping Curve", with its 0.6 exposure (float: every pixel
    // of every frame goes through it).
    const float v = 0.6f * x;
    const float y = v * (2.51f * v + 0.03f) / (v * (2.43f * v + 0.59f) + 0.14f);
    return std::min(1.0f, y);
}

namespace detail {

namespace {

// Fills f.refined for cell rows [cy0, cy1) (f.refined sized to the cells) from the G-buffer's
// samples of those rows; returns the number of those samples showing geometry.
int64_t markRows(FrameState& f, int64_t cy0, int64_t cy1) {
    const int s = f.adaptive;
    const GBuffer& g = f.gbuffer;
    const SceneGeometry& geo = f.geometry;
    const int64_t W = f.width, cw = f.width / s;
    // The face normals and meshes from the compact per-triangle records (16 bytes a triangle, kept
    // with the geometry) rather than the 84-byte bases: a random read per triangle that stays in the
    // cache beside the 4x G-buffer.
    const TriangleTag* tags = f.cache.triangleTags.data();
    const float cos30 = float(std::cos(30 * M_PI / 180));
    constexpr uint32_t kNone = GBuffer::kNone;
    // Whether the samples of a cell that do not all show one triangle ask for every sample shaded
    // (any of the reasons above): the background and the depths first (the samples' own arrays,
    // read in order), the meshes, face normals and materials (random reads per triangle) only
    // where those leave it open.
    const auto refineCell = [&](int64_t cx, int64_t cy) {
        const size_t at = size_t(cy * s * W + cx * s);
        const uint32_t first = g.triangle[at];
        float dmin = g.depth[at], dmax = dmin;
        bool mixed = false;
        for (int dy = 0; dy < s; ++dy)
            for (int dx = 0; dx < s; ++dx) {
                const size_t i = at + size_t(dy * W + dx);
                const uint32_t t = g.triangle[i];
                if (t == first) continue;
                if (t == kNone || first == kNone) return true;
                mixed = true;
                dmin = std::min(dmin, g.depth[i]);
                dmax = std::max(dmax, g.depth[i]);
            }
        if (!mixed) return false; // one triangle (or the background) over the cell
        if (dmax - dmin > 0.02f * dmin) return true;
        const TriangleTag& ft = tags[first];
        for (int dy = 0; dy < s; ++dy)
            for (int dx = 0; dx < s; ++dx) {
                const uint32_t t = g.triangle[at + size_t(dy * W + dx)];
                if (t == first) continue;
                // The same mesh (the tags' meshes with their opaque bit: equal only where the meshes
                // are), faces within 30 degrees (both sides of a face shade alike: the angle between
                // the lines) and the same material.
                const TriangleTag& tt = tags[t];
                if (((tt.mesh ^ ft.mesh) & kTagSurface) || std::abs(dot(tt.normal, ft.normal)) < cos30 ||
                    geo.triangleMaterial[t] != geo.triangleMaterial[first])
                    return true;
            }
        return false;
    };
    // One pass over the samples: each cell's refinement and the samples showing geometry (the
    // G-buffer pass's count, which would otherwise read them again).
    int64_t covered = 0;
    for (int64_t cy = cy0; cy < cy1; ++cy) {
        uint8_t* out = &f.refined[size_t(cy * cw)];
        if (s == 2) { // the default: one triangle over the cell needs no depth (most cells)
            const uint32_t* row0 = &g.triangle[size_t(cy * 2 * W)];
            const uint32_t* row1 = row0 + W;
            int64_t cx = 0;
#ifdef __AVX2__
            // Four cells at a time: whether each shows one triangle (a == b, a == c, b == d) and the
            // samples showing geometry, in vector compares; refineCell only for the others.
            const __m256i none = _mm256_set1_epi32(int(kNone));
            for (; cx + 4 <= cw; cx += 4) {
                const __m256i r0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row0 + 2 * cx));
                const __m256i r1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row1 + 2 * cx));
                // Lane 2k: a == c, 2k + 1: b == d; with the pair swapped, a == b in both.
                const __m256i same = _mm256_and_si256(
                    _mm256_cmpeq_epi32(r0, r1),
                    _mm256_cmpeq_epi32(r0, _mm256_shuffle_epi32(r0, _MM_SHUFFLE(2, 3, 0, 1))));
                const unsigned one = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(same)));
                const unsigned empty0 =
                    unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(r0, none))));
                const unsigned empty1 =
                    unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(r1, none))));
                covered += 16 - std::popcount(empty0) - std::popcount(empty1);
                if (one == 0xffu) { // the four cells each show one triangle (or the background)
                    std::memset(out + cx, 0, 4);
                    continue;
                }
                for (int k = 0; k < 4; ++k)
                    out[cx + k] =
                        ((one >> (2 * k)) & 3u) == 3u || !refineCell(cx + k, cy) ? 0 : kEveryRefinedSample;
            }
#endif
            for (; cx < cw; ++cx) {
                const uint32_t a = row0[2 * cx], b = row0[2 * cx + 1], c = row1[2 * cx], d = row1[2 * cx + 1];
                covered +=
                    int64_t(a != kNone) + int64_t(b != kNone) + int64_t(c != kNone) + int64_t(d != kNone);
                out[cx] = (a == b && a == c && a == d) || !refineCell(cx, cy) ? 0 : kEveryRefinedSample;
            }
            continue;
        }
        for (int64_t cx = 0; cx < cw; ++cx) {
            for (int dy = 0; dy < s; ++dy)
                for (int dx = 0; dx < s; ++dx)
                    covered += g.triangle[size_t((cy * s + dy) * W + cx * s + dx)] != kNone;
            out[cx] = refineCell(cx, cy) ? kEveryRefinedSample : 0;
        }
    }
    return covered;
}

} // namespace

int64_t markRefinedCells(FrameState& f) {
    const int s = f.adaptive;
    if (s <= 1) return -1;
    f.refined.resize(size_t((f.width / s) * (f.height / s)));
    return parallelReduce(
        int64_t(0), f.height / s, int64_t(8), int64_t(0),
        [&](int64_t y0, int64_t y1) { return markRows(f, y0, y1); },
        [](int64_t a, int64_t b) { return a + b; });
}

int64_t renderGBufferAndMark(FrameState& f, const Frame& camera, Progress* progress) {
    const int s = f.adaptive;
    if (s <= 1) {
        renderGBuffer(f.geometry, camera, f.gbuffer, progress);
        return -1;
    }
    const int64_t ch = f.height / s;
    f.refined.resize(size_t((f.width / s) * ch));
    // Each tile's cells marked as its rows are done, while its samples are still in the cache
    // (tiles of whole cell rows); the covered counts summed per tile, in order.
    std::vector<int64_t> covered(size_t(ch), 0);
    renderGBufferTiles(f.geometry, camera, f.gbuffer, s, progress, [&](int64_t y0, int64_t y1) {
        const int64_t cy0 = y0 / s, cy1 = std::min(ch, y1 / s);
        if (cy0 < cy1) covered[size_t(cy0)] = markRows(f, cy0, cy1);
    });
    int64_t sum = 0;
    for (const int64_t c : covered) sum += c;
    return sum;
}

namespace {

float lumaOf(const Vec3f& c) { return postLuma(c); }

} // namespace

// The perceptual luma of a shaded sample as the image shows it (after the output transform).
float shownLuma(const Vec3f& c, ToneMap t) { return lumaOf(t == ToneMap::Clamp ? c : filmicToneMapped(c)); }

bool curvesAcrossNeighbours(const FrameState& f, int64_t cx, int64_t cy, float contrast) {
    const int a = f.adaptive;
    const int64_t cw = f.width / a, ch = f.height / a;
    const ToneMap tm = f.options.toneMap;
    const auto luma = [&](int64_t x, int64_t y) {
        return shownLuma(f.shaded[representativeSample(f, x, y)], tm);
    };
    return curvesAcross(luma, cx, cy, cw, ch, contrast);
}

int cellSamples(const FrameState& f, int64_t cx, int64_t cy, std::array<std::size_t, 64>& out) {
    const int a = f.adaptive;
    const int64_t W = f.width;
    if (a <= 1) {
        out[0] = std::size_t(cy * W + cx);
        return 1;
    }
    const uint8_t kind = f.refined[size_t(cy * (W / a) + cx)];
    const std::size_t rep = representativeSample(f, cx, cy);
    int n = 0;
    for (int dy = 0; dy < a; ++dy)
        for (int dx = 0; dx < a; ++dx) {
            const bool shaded = kind == kEveryRefinedSample ? true
                                : kind == kRookSamples      ? dx == rookColumn(a, dy)
                                                            : dx == a / 2 && dy == a / 2;
            if (shaded) out[size_t(n++)] = std::size_t((cy * a + dy) * W + cx * a + dx);
        }
    for (int k = 1; k < n; ++k)
        if (out[size_t(k)] == rep) std::swap(out[0], out[size_t(k)]);
    return n;
}

int rookColumn(int s, int dy) {
    const int c = 2 * dy;
    return (s % 2 ? c : c + (c >= s)) % s;
}

bool shadedSample(const FrameState& f, int64_t x, int64_t y) {
    const int a = f.adaptive;
    if (a <= 1) return true;
    const int dx = int(x % a), dy = int(y % a);
    switch (f.refined[size_t((y / a) * (f.width / a) + x / a)]) {
    case kEveryRefinedSample:
        return true;
    case kRookSamples:
        return dx == rookColumn(a, dy);
    default:
        return dx == a / 2 && dy == a / 2;
    }
}

int64_t postCandidates(const float* row, const float* above, const float* below, const uint8_t* skipRow,
                       int64_t W, int64_t* out) {
    // The scalar test at pixel x (a neighbour past the row's end: the pixel at the end).
    const auto test = [&](int64_t x, int64_t& count) {
        const float m = row[x], n = above[x], s = below[x], e = row[x + 1 < W ? x + 1 : W - 1],
                    w = row[x > 0 ? x - 1 : 0];
        const float hi = std::max({m, n, s, e, w}), lo = std::min({m, n, s, e, w});
        out[count] = x; // listed without a branch (whether it passes is as good as random on foliage)
        count += int64_t(!(hi - lo < std::max(1.0f / 32, hi / 8))) & int64_t(!skipRow || !skipRow[x]);
    };
    int64_t count = 0, x = 0;
#ifdef __AVX2__
    // Eight pixels at a time inside the row (x - 1 and x + 8 in it): the same test in lanes (max,
    // min, hi / 8 as a product by 1/8, all exact), except that a lane with a NaN among its lumas is
    // listed (std::max / std::min would take it or not by its place).
    if (W >= 10) {
        const __m256 floor = _mm256_set1_ps(1.0f / 32), eighth = _mm256_set1_ps(1.0f / 8);
        test(0, count); // its west neighbour is itself
        for (x = 1; x + 8 <= W - 1; x += 8) {
            const __m256 m = _mm256_loadu_ps(row + x), n = _mm256_loadu_ps(above + x),
                         s = _mm256_loadu_ps(below + x), e = _mm256_loadu_ps(row + x + 1),
                         w = _mm256_loadu_ps(row + x - 1);
            const __m256 hi = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(m, n), _mm256_max_ps(s, e)), w);
            const __m256 lo = _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(m, n), _mm256_min_ps(s, e)), w);
            const __m256 limit = _mm256_max_ps(floor, _mm256_mul_ps(hi, eighth));
            const __m256 all = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(m, n), _mm256_add_ps(s, e)), w);
            unsigned bits = unsigned(
                _mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(_mm256_sub_ps(hi, lo), limit, _CMP_NLT_UQ),
                                                _mm256_cmp_ps(all, all, _CMP_UNORD_Q))));
            if (skipRow) { // the lanes whose skip byte is 0
                const __m128i skipped = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(skipRow + x));
                bits &= unsigned(_mm_movemask_epi8(_mm_cmpeq_epi8(skipped, _mm_setzero_si128()))) & 0xffu;
            }
            for (; bits != 0; bits &= bits - 1) out[count++] = x + std::countr_zero(bits);
        }
    }
#endif
    for (; x < W; ++x) test(x, count);
    return count;
}

Image postAntiAlias(const Image& in, const std::vector<uint8_t>& skip) {
    Image out = in;
    std::vector<float> luma;
    postAntiAlias(in, skip, out, luma, false);
    return out;
}

namespace {

// The post-process over `in` with its lumas `luma`, handing each blended pixel to
// write(y0, x, y, value) (y0: the first row of the 16 its row is processed with); reads `in` only.
template <class Write>
void postAntiAliasRows(const Image& in, const std::vector<uint8_t>& skip, const std::vector<float>& luma,
                       Write&& write) {
    const int64_t W = in.width, H = in.height;
    auto L = [&](int64_t x, int64_t y) {
        return luma[size_t(std::clamp<int64_t>(y, 0, H - 1) * W + std::clamp<int64_t>(x, 0, W - 1))];
    };
    auto C = [&](int64_t x, int64_t y) {
        return in.pixels[size_t(std::clamp<int64_t>(y, 0, H - 1) * W + std::clamp<int64_t>(x, 0, W - 1))];
    };
    constexpr int kSearch = 12;
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        std::vector<int64_t> candidates(size_t(W) + 1);
        for (int64_t y = y0; y < y1; ++y) {
            // The pixels the test below lets through, listed without a branch per pixel (whether
            // a pixel's contrast passes is as good as random on foliage: a mispredicted branch).
            const float* row = &luma[size_t(y * W)];
            const float* above = &luma[size_t(std::min(y + 1, H - 1) * W)];
            const float* below = &luma[size_t(std::max<int64_t>(y - 1, 0) * W)];
            const uint8_t* skipRow = skip.empty() ? nullptr : &skip[size_t(y * W)];
            const int64_t count = postCandidates(row, above, below, skipRow, W, candidates.data());
            for (int64_t c = 0; c < count; ++c) {
                const int64_t x = candidates[size_t(c)];
                const float m = L(x, y), n = L(x, y + 1), s = L(x, y - 1), e = L(x + 1, y), w = L(x - 1, y);
                const float hi = std::max({m, n, s, e, w}), lo = std::min({m, n, s, e, w});
                const float range = hi - lo;
                if (range < std::max(1.0f / 32, hi / 8)) continue;
                const float nw = L(x - 1, y + 1), ne = L(x + 1, y + 1), sw = L(x - 1, y - 1),
                            se = L(x + 1, y - 1);
                const float horizontal =
                    std::abs(nw + ne - 2 * n) + 2 * std::abs(w + e - 2 * m) + std::abs(sw + se - 2 * s);
                const float vertical =
                    std::abs(nw + sw - 2 * w) + 2 * std::abs(n + s - 2 * m) + std::abs(ne + se - 2 * e);
                // A horizontal edge (luma changes along y): the neighbours across it are s and n.
                const bool isHorizontal = horizontal >= vertical;
                const float l1 = isHorizontal ? s : w, l2 = isHorizontal ? n : e;
                const float g1 = l1 - m, g2 = l2 - m;
                const bool steepest1 = std::abs(g1) >= std::abs(g2);
                const float gradientScaled = 0.25f * std::max(std::abs(g1), std::abs(g2));
                const int side = steepest1 ? -1 : 1; // towards the steeper neighbour
                const float localAverage = 0.5f * ((steepest1 ? l1 : l2) + m);
                // Luma on the edge line (half-way to the neighbour across) at offset k along it.
                auto edgeLuma = [&](int64_t k) {
                    return isHorizontal ? 0.5f * (L(x + k, y) + L(x + k, y + side))
                                        : 0.5f * (L(x, y + k) + L(x + side, y + k));
                };
                float end1 = 0, end2 = 0;
                int d1 = kSearch, d2 = kSearch;
                for (int k = 1; k <= kSearch; ++k) {
                    end1 = edgeLuma(-k) - localAverage;
                    if (std::abs(end1) >= gradientScaled) {
                        d1 = k;
                        break;
                    }
                }
                for (int k = 1; k <= kSearch; ++k) {
                    end2 = edgeLuma(k) - localAverage;
                    if (std::abs(end2) >= gradientScaled) {
                        d2 = k;
                        break;
                    }
                }
                const bool nearer1 = d1 < d2;
                const float dist = float(std::min(d1, d2)), thickness = float(d1 + d2);
                const float pixelOffset = 0.5f - dist / thickness;
                const bool centreSmaller = m < localAverage;
                const bool correct = ((nearer1 ? end1 : end2) < 0) != centreSmaller;
                float offset = correct ? pixelOffset : 0;
                // Sub-pixel aliasing: the 3 x 3 low-pass against the centre.
                const float average = (2 * (n + s + e + w) + nw + ne + sw + se) / 12;
                const float sub1 = std::clamp(std::abs(average - m) / range, 0.0f, 1.0f);
                const float sub2 = (-2 * sub1 + 3) * sub1 * sub1;
                offset = std::clamp(std::max(offset, sub2 * sub2 * 0.75f), 0.0f, 1.0f);
                const Vec3f across = isHorizontal ? C(x, y + side) : C(x + side, y);
                write(y0, x, y, in.at(x, y) * (1 - offset) + across * offset);
            }
        }
    });
}

} // namespace

void postAntiAlias(const Image& in, const std::vector<uint8_t>& skip, Image& out, std::vector<float>& luma,
                   bool lumaGiven) {
    const int64_t W = in.width, H = in.height;
    if (W < 3 || H < 3) return;
    if (!lumaGiven) {
        luma.resize(in.pixels.size());
        parallelFor(0, H, 64, [&](int64_t y0, int64_t y1) {
            for (std::size_t i = size_t(y0 * W); i < size_t(y1 * W); ++i) luma[i] = lumaOf(in.pixels[i]);
        });
    }
    postAntiAliasRows(in, skip, luma,
                      [&](int64_t, int64_t x, int64_t y, const Vec3f& v) { out.at(x, y) = v; });
}

void postAntiAliasInPlace(Image& image, const std::vector<uint8_t>& skip, const std::vector<float>& luma,
                          std::vector<std::vector<std::pair<std::size_t, Vec3f>>>& blends) {
    const int64_t W = image.width, H = image.height;
    if (W < 3 || H < 3) return;
    // Each band of 16 rows keeps its blends until every band has read its neighbours' pixels.
    blends.resize(size_t((H + 15) / 16));
    for (auto& b : blends) b.clear();
    postAntiAliasRows(image, skip, luma, [&](int64_t y0, int64_t x, int64_t y, const Vec3f& v) {
        blends[size_t(y0 / 16)].push_back({size_t(y * W + x), v});
    });
    parallelFor(0, int64_t(blends.size()), 1, [&](int64_t b0, int64_t b1) {
        for (int64_t b = b0; b < b1; ++b)
            for (const auto& [i, v] : blends[size_t(b)]) image.pixels[i] = v;
    });
}

} // namespace detail
} // namespace voxfx
