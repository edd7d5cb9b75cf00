// voxfx — ED06 §3.3 frosted glass. Glass method "frosted" (voxfx/glass.hpp).
//
// The glass's front faces and back faces (seen from the eye) are voxelized into two slicemaps in a
// camera-aligned perspective frame (gridResolution columns across, as many slices over the glass's
// depth range); each pixel's column is walked front to back counting inside cells (a front-only
// cell enters, a back-only cell leaves, a cell with both is resolved by the state carried from the
// previous cell: from outside a thin sliver, from inside the way out; it counts once and leaves the
// ray outside, which errs thin rather than filling the rest of the column). The count gives the
// thickness L the eye ray crosses; the light comes from the refracted direction displaced by L,
// attenuated by exp(-sigma L), blurred over a cone that grows with L (a lookup into the
// environment's pre-filtered pyramid).
//
// Thread-safety: read-only after construction; trace may run from any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"

namespace voxfx {

struct GlassInput;

struct FrostedGlassOptions : GlassSceneOptions {
    static constexpr std::string_view kName = "frosted";
    static constexpr std::string_view kSummary =
        "ED06: thickness from front/back-face slicemaps drives a refraction offset, attenuation and a "
        "blurred environment lookup";
    int64_t gridResolution = kGlassGridResolution; ///< slicemap columns across and slices, 2..4096
    /// Blur cone angle (radians) of the environment seen through a thickness equal to the glass
    /// bounds' diagonal (proportional below it).
    double blur = 0.6;
    /// glassGrid, frostedBlur, sceneBehind.
    static std::span<const OptionField<FrostedGlassOptions>> fields();
};

class FrostedGlass {
public:
    using Options = FrostedGlassOptions;
    /// `camera`: the view's perspective frame (the G-buffer's). Throws voxfx::Error for an
    /// orthographic camera, mismatched sizes, a resolution outside 2..4096 or glass behind the eye.
    FrostedGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media,
                 const Frame& camera, const FrostedGlassOptions& options);
    static FrostedGlass build(const GlassInput& input, const FrostedGlassOptions& options);
    /// Inside cells counted in the column of world point p (see the file comment), from p's cell on.
    int64_t insideCells(const Vec3d& p) const;
    /// World length the eye ray through p crosses inside the glass (insideCells times the slice's
    /// length along that ray).
    double thickness(const Vec3d& p) const;
    GlassPath trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir) const;
    GlassPath trace(const GlassHit& h) const { return trace(h.entry, h.normal, h.medium, h.dir); }
    const BitGrid& front() const { return front_; }
    const BitGrid& back() const { return back_; }
    const Frame& frame() const { return frame_; }

private:
    Frame frame_;
    BitGrid front_, back_;
    std::vector<GlassMedium> media_;
    double diagonal_ = 1;
    double blur_ = FrostedGlassOptions{}.blur;
};

} // namespace voxfx
