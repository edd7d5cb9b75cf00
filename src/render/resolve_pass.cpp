// voxfx — the renderer's resolve pass (render/frame_passes.hpp): from the shaded samples to the
// image.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "render/antialias.hpp"
#include "render/frame_passes.hpp"
#include "render/render_cache.hpp"
#include "render/vec_simd.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"

namespace voxfx::detail {

namespace {

// The output transform of one sample (t resolved: filmic or linear).
Vec3f toneMapped(const Vec3f& c, ToneMap t) {
    if (t == ToneMap::Clamp) return c;
    return filmicToneMapped(c); // filmicToneMap per component, in lanes
}

// The tone-mapped sum of the samples of cell (cx, cy) that the passes shaded, each times `scale`:
// all a x a of a refined cell; the mean of its N-rooks samples (glass inside), or its one
// representative sample, a x a times, elsewhere (adaptive anti-aliasing left the others unshaded).
// Without a tone map (`t` null): the linear sum.
[[gnu::always_inline]] inline Vec3f cellSum(const FrameState& f, int64_t cx, int64_t cy, const ToneMap* t,
                                            float scale) {
    const int a = f.adaptive;
    const int64_t W = f.width, sx = cx * a, sy = cy * a;
    const uint8_t kind = f.refined.empty() ? kEveryRefinedSample : f.refined[size_t(cy * (W / a) + cx)];
    auto out = [&](const Vec3f& c) { return t ? toneMapped(c * scale, *t) : c * scale; };
    Vec3f sum;
    if (kind == kEveryRefinedSample) {
        // A sample with the same shading as the one before it (the shading pass copies a shading
        // to the samples showing its triangle) reuses its transform: the same terms summed.
        const Vec3f* last = nullptr;
        Vec3f mapped;
        for (int dy = 0; dy < a; ++dy)
            for (int dx = 0; dx < a; ++dx) {
                const Vec3f& c = f.shaded[size_t((sy + dy) * W + sx + dx)];
                if (!last || std::memcmp(&c, last, sizeof(Vec3f)) != 0) mapped = out(c);
                last = &c;
                sum += mapped;
            }
        return sum;
    }
    if (kind == kRookSamples) {
        Vec3f mean;
        for (int dy = 0; dy < a; ++dy) mean += f.shaded[size_t((sy + dy) * W + sx + rookColumn(a, dy))];
        return out(mean * (1.0f / float(a))) * float(a * a);
    }
    return out(f.shaded[size_t((sy + a / 2) * W + sx + a / 2)]) * float(a * a);
}

// Automatic exposure (Reinhard et al. 2002, eq. 1): key / the log-average luminance of the frame's
// cells, exp(mean of log(1e-4 + L)). Rows are summed in order (deterministic for any thread count).
float autoExposureScale(const FrameState& f) {
    constexpr double kKey = 0.18, kDelta = 1e-4;
    const int a = std::max(f.adaptive, 1);
    const int64_t cw = f.width / a, ch = f.height / a;
    std::vector<double> rows(size_t(ch), 0.0);
    parallelFor(0, ch, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const Vec3f c = cellSum(f, cx, cy, nullptr, 1.0f / float(a * a));
                rows[size_t(cy)] +=
                    std::log(kDelta + std::max(0.0, 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z));
            }
    });
    double sum = 0;
    for (const double r : rows) sum += r;
    const double logAverage = std::exp(sum / double(std::max<int64_t>(1, cw * ch)));
    return float(std::clamp(kKey / logAverage, 1e-6, 1e6));
}

} // namespace

// Box filter of the k x k (times adaptive) samples of each pixel, each tone-mapped first (so an edge
// against a bright sky keeps its coverage), and flip: frame rows run up, image rows down. Then the
// post-process anti-aliasing on the pixels adaptive sampling did not refine (nor touch).
void resolvePass(FrameState& f, Progress*) {
    const RenderOptions& o = f.options;
    const int k = o.supersample * f.adaptive, a = f.adaptive;
    const int64_t W = f.width, cw = f.width / std::max(a, 1), w = o.width, h = o.height;
    RenderResult& r = f.result;
    RenderCacheData::Resolve& scratch = f.cache.resolve;
    const bool post = o.antiAliasing == AntiAliasing::Post || o.antiAliasing == AntiAliasing::Full;
    // The box-filtered image, which the post-process then blends in place.
    r.image = Image(w, h);
    Image& filtered = r.image;
    // Per output pixel (image rows): 1 where a cell of it was shaded at every sample.
    std::vector<uint8_t>& refined = scratch.refined;
    refined.resize(size_t(w * h));
    const float norm = 1.0f / float(k * k);
    // Auto: render() writes no file, so the display's filmic (toneMapForImage).
    const ToneMap toneMap = toneMapForImage(o.toneMap, {});
    const int cells = o.supersample; // cells of a x a samples per pixel side
    const float scale = f.autoExposure ? autoExposureScale(f) : 1.0f;
    std::vector<float>& luma = scratch.luma;
    if (post) luma.resize(size_t(w * h));
    r.exposure = f.autoExposure ? scale : o.exposure;
    parallelFor(0, h, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y) {
            for (int64_t x = 0; x < w; ++x) {
                Vec3f sum;
                uint8_t every = 0;
                for (int cy = 0; cy < cells; ++cy)
                    for (int cx = 0; cx < cells; ++cx) {
                        sum += cellSum(f, x * cells + cx, y * cells + cy, &toneMap, scale);
                        if (!f.refined.empty())
                            every |= f.refined[size_t((y * cells + cy) * cw + x * cells + cx)] ==
                                     kEveryRefinedSample;
                    }
                const Vec3f c = sum * norm;
                filtered.at(x, h - 1 - y) = c;
                refined[size_t((h - 1 - y) * w + x)] = every;
            }
            // The post-process's luma of the row, made here while it is in the cache.
            if (post)
                for (std::size_t i = size_t((h - 1 - y) * w), e = i + size_t(w); i < e; ++i)
                    luma[i] = postLuma(filtered.pixels[i]);
        }
    });
    for (const uint8_t v : refined) r.refinedPixels += v;
    if (post) {
        // Pixels next to a refined one keep their samples' coverage too.
        // The 3 x 3 dilation of `refined`, as a row pass then a column pass.
        std::vector<uint8_t>& skip = scratch.skip;
        std::vector<uint8_t>& rows = scratch.rows;
        skip.assign(refined.size(), 0);
        if (r.refinedPixels > 0) {
            rows.resize(refined.size());
            parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
                for (int64_t y = y0; y < y1; ++y) {
                    const uint8_t* in = &refined[size_t(y * w)];
                    uint8_t* out = &rows[size_t(y * w)];
                    for (int64_t x = 0; x < w; ++x)
                        out[x] = in[x] | (x > 0 ? in[x - 1] : 0) | (x + 1 < w ? in[x + 1] : 0);
                }
            });
            parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
                for (int64_t y = y0; y < y1; ++y) {
                    const uint8_t* above = &rows[size_t(std::max<int64_t>(0, y - 1) * w)];
                    const uint8_t* at = &rows[size_t(y * w)];
                    const uint8_t* below = &rows[size_t(std::min(h - 1, y + 1) * w)];
                    uint8_t* out = &skip[size_t(y * w)];
                    for (int64_t x = 0; x < w; ++x) out[x] = above[x] | at[x] | below[x];
                }
            });
        }
        postAntiAliasInPlace(r.image, skip, luma, scratch.blends);
    }
    if (f.glassSamples.empty()) return;
    r.glassMask.assign(size_t(w * h), 0);
    parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < w; ++x) {
                uint8_t any = 0;
                for (int dy = 0; dy < k; ++dy)
                    for (int dx = 0; dx < k; ++dx)
                        any |= f.glassSamples[size_t((y * k + dy) * W + x * k + dx)];
                r.glassMask[size_t((h - 1 - y) * w + x)] = any;
            }
    });
    for (const uint8_t v : r.glassMask) r.glass.pixels += v;
}

} // namespace voxfx::detail
