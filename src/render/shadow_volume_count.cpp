// voxfx — shadow volumes' counting: the volumes kept, extruded to their far planes, rasterized
// over the camera's G-buffer by the one rasterizer, a signed crossing count per pixel.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "render/shadow_volume_internal.hpp"

namespace voxfx::detail::shadowvolume {

namespace {

// Per-pixel signed crossing counts (see the file comment of shadow_volume.hpp).
struct SvCountConsumer {
    int64_t width;
    const float* depth;
    const uint8_t* mode;
    int32_t* count;
    std::atomic<int64_t>* fragments;
    struct Sink {
        int64_t width;
        const float* depth;
        const uint8_t* mode;
        int32_t* count;
        std::atomic<int64_t>* fragments;
        int64_t local = 0;
        void fragment(int64_t x, int64_t y, double d, uint32_t triangle, bool front) {
            ++local;
            const auto i = size_t(y * width + x);
            const double g = double(depth[i]);
            if (!std::isfinite(g)) return;
            if (mode[triangle]) {
                if (d > g) count[i] += front ? -1 : 1;
            } else if (d < g) {
                count[i] += front ? 1 : -1;
            }
        }
        void finish() { fragments->fetch_add(local, std::memory_order_relaxed); }
    };
    Sink tile(const Tile&) const { return {width, depth, mode, count, fragments}; }
};

} // namespace

void svCount(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup, const SvDecision& d,
             const GBuffer& gbuffer, ShadowVolumeMask& out) {
    ShadowVolumeStats& st = out.stats;
    auto t0 = SvClock::now();
    Mesh volumes;
    std::vector<uint8_t> mode;
    for (std::size_t i = 0; i < casters.casters.size(); ++i) {
        if (!d.keep[i]) continue;
        (setup[i].depthPass ? st.depthPass : st.depthFail)++;
        svAppendVolume(casters.casters[i], setup[i], d.cap[i].empty() ? setup[i].unlit : d.cap[i], d.far[i],
                       d.runs[i], volumes, mode, st.silhouetteEdges);
    }
    st.volumeTriangles = int64_t(mode.size());
    st.buildMs = svMsSince(t0);

    t0 = SvClock::now();
    const Frame& cam = gbuffer.frame;
    std::vector<int32_t> count(size_t(cam.width() * cam.height()), 0);
    std::atomic<int64_t> fragments{0};
    if (!volumes.indices.empty()) {
        SvCountConsumer consumer{cam.width(), gbuffer.depth.data(), mode.data(), count.data(), &fragments};
        RasterOptions ro;
        rasterize<Coverage::Center>(cam, volumes.view(), ro, consumer);
    }
    st.fragments = fragments.load();
    for (std::size_t i = 0; i < count.size(); ++i)
        out.shadowed[i] = gbuffer.triangle[i] != GBuffer::kNone && count[i] != 0;
    st.rasterMs = svMsSince(t0);
}

} // namespace voxfx::detail::shadowvolume
