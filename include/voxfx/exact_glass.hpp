// voxfx — exact glass: ray tracing on the actual triangles (Embree 3, voxfx/triangle_tracer.hpp),
// the reference for the voxel methods. Glass method "exact" (voxfx/glass.hpp).
//
// Objects may nest (CHANG §4.2, fig. 3: an angel inside a glass ball) and touch: the tracer keeps
// the stack of media the ray is in (closed meshes; entering a front face pushes its medium, leaving
// a back face removes the innermost copy of its medium; the top is the medium the ray is in, air
// when empty). Faces at the same point (two objects touching, found within the tracer's epsilon)
// are crossed together as one interface, from the medium before all of them to the medium after.
// Snell's law at every interface with n_from / n_to and the interpolated vertex normal, total
// internal reflection where Snell has no solution (the stack unchanged), (1 - F(n_from, n_to)) at
// every refraction, the tint of each medium entered, Beer–Lambert exp(-sigma * length) with the
// sigma of the medium each segment is in, until the ray is back in air and meets nothing (or
// maxEvents: it then leaves along its current direction); then the environment. A back face of a
// medium the ray is not in (an open mesh seen from outside) is passed through.
//
// Thread-safety: read-only after construction; trace may run from any number of threads.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "voxfx/glass_optics.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"

namespace voxfx {

class TriangleTracer;
struct GlassInput;
namespace detail {
class MediaStack;
}

class ExactGlass {
public:
    using Options = ExactGlassOptions;
    /// `mesh`: the glass triangles (world space, outward CCW); `vertexNormals`: one unit normal per
    /// vertex for smooth shading, or empty (face normals); `triangleMedium`: index into `media` per
    /// triangle. Throws voxfx::Error for mismatched sizes or when the Embree module is missing.
    ExactGlass(const MeshView& mesh, std::vector<Vec3f> vertexNormals, std::vector<uint32_t> triangleMedium,
               std::vector<GlassMedium> media);
    static ExactGlass build(const GlassInput& input, const ExactGlassOptions& options);
    /// Traces origin + t * dir (unit) through the glass (see the file comment).
    GlassPath trace(const Vec3d& origin, const Vec3d& dir, int maxEvents) const;
    /// The camera ray of `hit`, from the eye, with the options' maxEvents.
    GlassPath trace(const GlassHit& hit) const { return trace(hit.eye, hit.dir, maxEvents_); }

private:
    std::vector<Vec3f> normals_;

public:
    /// What a hit on a glass triangle reads, in one record (80 bytes) instead of five arrays (the
    /// indices, three vertex normals, a corner, the face normal, the medium: a cache miss each).
    struct Face {
        Vec3d normal;          ///< outward unit face normal: normalize(cross(b - a, c - a)), float corners
        Vec3f corner;          ///< corner a
        uint32_t medium;       ///< index into the media
        Vec3f vertexNormal[3]; ///< the corners' normals (zero without vertex normals)
    };

private:
    std::vector<Face> faces_;
    std::vector<uint32_t> medium_;
    std::vector<GlassMedium> media_;
    std::shared_ptr<const TriangleTracer> tracer_; ///< the glass triangles
    /// With several media: each medium's triangles (indices into the glass triangles) and a tracer
    /// over them alone, to find the faces of other media that coincide with a hit.
    struct MediumTriangles {
        uint32_t medium = 0;
        std::vector<uint32_t> triangle;
        std::shared_ptr<const TriangleTracer> tracer;
        /// Its triangles' bounds grown by twice the glass tracer's epsilon: a crossing farther out
        /// cannot lie on one of them, and is not queried.
        Box3d reach;
        /// A coarse grid over `reach` (cells per axis in `cells`, a bit per cell, x fastest): set
        /// where a triangle's bounds, grown by three epsilons, overlap the cell. A crossing in a clear
        /// cell is not queried either (the query reaches one epsilon from it).
        std::array<int, 3> cells{0, 0, 0};
        Vec3d cellScale{0, 0, 0}; ///< cells per world unit along each axis
        std::vector<uint64_t> occupied;
        bool mayTouch(const Vec3d& x) const;
        int cellAlong(int axis, double v) const; ///< the grid's cell index of coordinate v, clamped
    };
    std::vector<MediumTriangles> byMedium_;
    static void markOccupied(MediumTriangles& mt, const Mesh& sub, double grow);
    /// One face of a crossing: its medium and whether the ray enters its object there.
    struct CrossedFace {
        uint32_t medium;
        bool entering;
    };
    /// Every face the ray from direction d crosses at x, where it hit triangle t: t's and those of
    /// other media lying on it (two objects touching).
    void facesAt(const Vec3d& x, const Vec3d& d, uint32_t t, std::vector<CrossedFace>& faces) const;
    /// The media after crossing `faces` from `stack`, into `next`; multiplies `tint` by the tint of
    /// each medium entered. False where no medium changes (the faces are passed through).
    bool mediaAfter(const std::vector<CrossedFace>& faces, const detail::MediaStack& stack,
                    detail::MediaStack& next, Vec3f& tint) const;
    int maxEvents_ = ExactGlassOptions{}.maxEvents;
};

} // namespace voxfx
