// voxfx — glass: refraction through transparent objects, by voxels and by an exact reference; the
// closed set of glass methods the renderer uses, one room each.
//
// Materials with transmission > 0 (KHR_materials_transmission) and no gaps (opacity 1) are glass
// (Material::isGlass; a leaf's transmission with opacity < 1 is a sheet). A camera ray that hits
// glass (the G-buffer's nearest surface) splits at that front surface, with the exact dielectric
// Fresnel factor F (unpolarized, the same in every method): F of the environment seen along the
// mirror direction, plus (1 - F) times the light that comes through, tinted by the base colour.
// What comes through depends on the method:
//
//   none         glass is shaded like any surface
//   exact        voxfx/exact_glass.hpp: ray tracing on the triangles with Embree (the reference)
//   multi        voxfx/voxel_glass.hpp: CHANG §4.1.1 multiple refraction through an attribute grid
//   two-surface  voxfx/voxel_glass.hpp: Wyman 2005, refraction at the front and first back surface
//   frosted      voxfx/frosted_glass.hpp: ED06 §3.3, thickness from front/back-face slicemaps
//
// The renderer then looks up what the leaving ray meets: the opaque scene (sceneBehind, the same
// exact ray cast for every method, so the methods differ only inside the glass) or the environment.
//
// A method is an options type O and a built type G, G::Options = O, as the shadow techniques are
// (voxfx/shadow.hpp): O::kName, O::kSummary, O::fields(); G::build(input, o) from the glass
// triangles; g.trace(hit) -> GlassPath. GlassMethods lists them; GlassOptions and BuiltGlass are
// variants over them. The options and GlassOptions are in voxfx/glass_options.hpp, what
// voxfx/render.hpp includes. Adding a method is its own files, its options in
// voxfx/glass_options.hpp (and their entry in GlassOptions), and one entry in GlassMethods.
//
// Thread-safety: built methods are read-only; trace may run from any number of threads.
#pragma once

#include <concepts>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "voxfx/exact_glass.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/frosted_glass.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/image.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/voxel_glass.hpp"

namespace voxfx {

/// What a method is built from: the glass triangles of the scene (world space, outward CCW), one
/// unit normal per vertex (or empty: face normals), the medium of each triangle (index into media),
/// and the camera's perspective frame (the G-buffer's).
struct GlassInput {
    MeshView mesh;
    std::vector<Vec3f> vertexNormals;
    std::vector<uint32_t> triangleMedium;
    std::vector<GlassMedium> media;
    Frame camera;
};

class NoGlass {
public:
    using Options = NoGlassOptions;
    static NoGlass build(const GlassInput&, const NoGlassOptions&) { return {}; }
    GlassPath trace(const GlassHit&) const { return {}; }
};

/// The interface every glass method has (see the file comment).
template <class G>
concept GlassMethod = NamedOptions<typename G::Options> &&
    requires(const G& g, const GlassInput& in, const typename G::Options& o, const GlassHit& h) {
    { G::build(in, o) } -> std::same_as<G>;
    { g.trace(h) } -> std::same_as<GlassPath>;
};

template <GlassMethod... G> struct GlassMethodList {
    using Options = std::variant<typename G::Options...>;
    using Built = std::variant<G...>;
};

/// Every glass method, in the order the CLI lists them.
using GlassMethods = GlassMethodList<NoGlass, ExactGlass, MultiGlass, TwoSurfaceGlass, FrostedGlass>;
// GlassOptions (voxfx/glass_options.hpp) is the variant over this list's options.
static_assert(std::is_same_v<GlassOptions, GlassMethods::Options>,
              "GlassOptions (voxfx/glass_options.hpp) lists the methods of GlassMethods, in its order");
/// A built method.
using BuiltGlass = GlassMethods::Built;

/// The voxel glass grid render() builds, and why.
struct GlassGridChoice {
    int64_t resolution = 0;  ///< voxels along the glass's longest side
    double objectPixels = 0; ///< auto: the largest glass object's extent on screen, output pixels
    std::string reason;      ///< "given", or "auto: ..." (the time line prints it)
};
/// The grid of a voxel method: `requested` when it is not 0 (kGlassGridAuto); else about one voxel
/// per 1.5 output pixels of the glass object that spans the most pixels on screen (the longest side
/// of its bounding box's projection, clipped to the image), carried over to the longest side of
/// the glass's bounds, rounded up to a multiple of 32 (a camera that moves a little keeps its grid),
/// within kGlassGridAutoMin..kGlassGridAutoMax and at most 2^24 voxels over `glassBounds`.
/// `objects`: each glass object's world bounds; `view`: the camera's frame, `pixelsPerColumn` the
/// output pixels per column of it (1 / supersampling). No object in front of the camera: the minimum.
GlassGridChoice chooseGlassGrid(int64_t requested, std::span<const Box3d> objects, const Box3d& glassBounds,
                                const Frame& view, double pixelsPerColumn);

/// Builds the method `options` holds.
BuiltGlass buildGlass(const GlassInput& input, const GlassOptions& options);
GlassPath traceGlass(const BuiltGlass& glass, const GlassHit& hit);

/// Mean absolute error and PSNR of `test` against `reference` over the pixels where mask != 0,
/// values clamped to [0, 1] per channel first (peak 1). psnr is +inf for identical images.
struct ImageError {
    double mae = 0, psnr = 0;
    int64_t pixels = 0;
};
ImageError imageError(const Image& test, const Image& reference, const std::vector<uint8_t>& mask);

} // namespace voxfx
