// voxfx — the renderer's glass pass (internal): replaces the shading of the pixels that show glass
// with the light that comes through them (voxfx/glass.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "render/frame_state.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx::detail {

/// What the glass pass builds from the scene before tracing: the method's structures, the tracer of
/// the opaque scene behind the glass, and the media. Kept by the RenderCache while the meshes,
/// materials and glass options (and, for a view-dependent method, the camera) stay the same.
struct GlassSetup {
    bool any = false;                     ///< some triangle is glass (otherwise nothing below is built)
    std::vector<uint8_t> isGlass;         ///< per material
    std::vector<uint32_t> opaqueTriangle; ///< per triangle of `behind`: its index in the scene
    BuiltGlass built;
    std::unique_ptr<TriangleTracer> behind; ///< null: the environment alone behind the glass
    /// Per triangle of `behind`: the triangles of `behind` sharing each of its edges (by vertex
    /// index), or kNoTriangle (the glass lattice interpolates only between paths that land on one
    /// triangle or on two that meet along an edge).
    std::vector<std::array<uint32_t, 3>> behindNeighbours;
    static constexpr uint32_t kNoTriangle = ~uint32_t(0);
    double epsilon = 1e-6;
};

/// With a glass method other than none: shades the glass samples of frame.shaded with it, marks them
/// in frame.glassSamples (one entry per sample) and records the method's times in frame.result.glass.
void shadeGlass(FrameState& frame);

} // namespace voxfx::detail
