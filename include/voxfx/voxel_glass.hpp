// voxfx — the voxel glass methods: a camera ray refracted at the glass's front surface marches
// through an attribute grid of the glass (normals and material per voxel; one voxel at a time with
// the one DDA, voxfx/dda.hpp). Glass methods "multi" and "two-surface" (voxfx/glass.hpp). A voxel's
// normal is the mean of its writes' normals: the renderer's vertex normals interpolated at the
// point of each triangle nearest the voxel's centre (the smooth surface the front surface and the
// exact tracer are shaded with; on a 15-degree tessellation the facets' own normals are 3.8 degrees
// off on average, up to 9), or the face normals where no vertex normals are given.
//
//   multi        CHANG §4.1.1 multiple refraction, with the objects of several materials of §4.2
//                (nested and touching glass): the march keeps the stack of media the ray is in
//                (material ids). A boundary voxel whose stored normal faces the ray enters the
//                voxel's material (unless the ray is in it already); one whose normal points along
//                the ray leaves its material (or, where the ray is not in that material, the
//                innermost one). Snell with the normal where the surface crosses the ray: the middle
//                of the run of that surface's voxels along the ray (written, of its material, facing
//                the same way, within 30 degrees of the first; up to 6 past the first), not the
//                first voxel met (leaving a convex surface, the normal there is tilted further from
//                the ray: false total reflections near the critical angle); the event itself stays
//                mid-way through the first voxel. That normal is trilinear over the eight voxel
//                centres around the crossing that hold a normal of that material within 30 degrees
//                of the voxel's own (a voxel's averaged normal alone is a staircase of the faces
//                touching it: a few degrees off, enough for a false total reflection near the
//                critical angle). A crease voxel (faces of two surfaces meeting at an edge: the mean
//                of their normals is no face's, 45 degrees off at a box's edge; told by the length
//                of the normal sum, below cos 30 degrees of the writes) is no crossing where the ray
//                goes on into a voxel of one surface that it crosses (within 6 voxels of the
//                material); otherwise, leaving, it takes the normal of its one-surface neighbour
//                closest to the ray's direction (the face the ray heads into most directly). A voxel
//                the surface touches only at a corner the ray does not pass is no crossing either:
//                the ray goes on into voxels nothing wrote and then meets the same surface again,
//                facing the same way (within 30 degrees), before any voxel of its other side. Snell
//                with n_from / n_to of the media on both sides, (1 - F(n_from, n_to)), the
//                tint of a medium entered; total internal reflection where there is no solution (the media
//                unchanged); a refraction is skipped when its voxel has the material of the last surface and
//                its normal is within angleThreshold of that surface's (CHANG's guard against refracting
//                twice at one surface spread over neighbouring voxels); Beer–Lambert with the coefficient of
//                the medium the ray is in, per voxel segment; until the ray leaves the grid. What
//                comes through is then looked up (the opaque scene or the environment) along the
//                last direction from where the ray last left glass (the start of that boundary
//                voxel), or from its last event if it never left (a missed exit): never from the
//                grid's edge, which lies a voxel beyond the glass (below the ground under glass
//                standing on it). A sheet thinner than a voxel writes its front and back faces into
//                the same voxels, whose normals cancel (the write count tells it: |sum| below half
//                the writes): met from inside its material such a voxel is the exit, through a face
//                parallel to the entry face; met from outside, the ray crosses the whole sheet there
//                (two Fresnel passes, half a voxel of attenuation, direction unchanged). Faces of two
//                materials lying on each other (touching glasses, CHANG §4.2) also share voxels whose
//                normals cancel, but they are no sheet: they are one face between two media. A second
//                voxelization with the triangles in reverse order finds the voxels two materials wrote
//                (their first and last writers' materials), and a normals-only voxelization of the
//                triangles of one of the two (those whose id has the lowest bit in which the two ids
//                differ set) gives the face's normal there. Met from within one of the two media, the
//                ray crosses into the other where it heads out of the one it is in (Snell with
//                n_from / n_to and the face's normal trilinear over its voxels around the crossing, the
//                entered medium's tint) and passes the face's other voxels. Along the edge where that
//                face meets the outside, the glasses' outer faces share voxels too: a ray in either
//                medium is inside such a voxel's material (its outer face is not a second entry).
//   two-surface  Wyman 2005 as CHANG's baseline: the same march stops at the first back surface: one
//                refraction there (or the mirror direction under total internal reflection), then the
//                environment. It cannot see a second part of the object behind the first.
//
// The grid has cubic voxels, gridResolution along the longest side of the glass's bounds (one voxel
// of margin on each side).
//
// Thread-safety: read-only after construction; trace may run from any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "voxfx/attribute_grid.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

struct GlassInput;

/// The attribute grid (normals and material channel) of the glass triangles, and the march.
class VoxelGlass {
public:
    /// Voxelizes `mesh` (world space) into cubic voxels, options.gridResolution along the longest side
    /// of its bounds (one voxel of margin), with options.coverage. With `vertexNormals` (one unit
    /// normal per vertex, as the renderer shades with) the voxels hold those normals interpolated
    /// over each triangle, else the face normals. Resolution 0 (auto; render() sizes it from the
    /// screen first: chooseGlassGrid) is kGlassGridResolution here. Throws voxfx::Error for a
    /// resolution outside 2..4096 (other than 0), mismatched sizes or no triangles.
    VoxelGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media,
               const VoxelGlassOptions& options, std::span<const Vec3f> vertexNormals = {});
    /// The path of a camera ray along unit `dir` that meets glass at `entry` (a surface point found by
    /// rasterization) with unit outward normal `normal` and medium `medium`; `twoSurface` stops at
    /// the first back surface (see the file comment).
    GlassPath trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                    const VoxelGlassOptions& options, bool twoSurface) const;
    const AttributeGrid& grid() const { return grid_; }
    double voxelSize() const { return voxel_; }

private:
    AttributeGrid grid_;
    /// Per voxel, 1 where triangles of two materials wrote it (faces of two media lying on each
    /// other): their normals cancel as a thin sheet's do, but they are not a sheet. Empty when the
    /// glass is of one material.
    std::vector<uint8_t> twoMaterials_;
    /// A voxel two materials wrote: the materials of its first and last write (lo, hi); whether it
    /// is on the face between two touching media (their normals cancel), and then lo's outward unit
    /// normal there (zero where it could not be told). One per such voxel, sorted by voxel.
    struct Interface {
        int64_t voxel;
        uint32_t lo, hi;
        bool between;
        Vec3f normalLo;
    };
    std::vector<Interface> interfaces_;
    const Interface* interfaceAt(int64_t voxel) const;
    Vec3d interfaceNormalAt(const Vec3d& g, const Interface& own) const;
    std::vector<GlassMedium> media_;
    Vec3d origin_;
    double voxel_ = 1;
    /// One ray's march (render/voxel_glass_march.cpp): the walk, and a function per kind of voxel.
    struct March;
};

/// A voxel glass method: the march of VoxelGlass with the options O, stopping at the first back
/// surface when kTwoSurface.
template <class O, bool kTwoSurface> class VoxelGlassMethod {
public:
    using Options = O;
    /// Voxelizes the glass of `input` (VoxelGlass's constructor; it throws as that does).
    static VoxelGlassMethod build(const GlassInput& input, const O& options);
    GlassPath trace(const GlassHit& h) const {
        return voxels_.trace(h.entry, h.normal, h.medium, h.dir, options_, kTwoSurface);
    }
    const VoxelGlass& voxels() const { return voxels_; }

private:
    VoxelGlassMethod(VoxelGlass voxels, const O& options) : voxels_(std::move(voxels)), options_(options) {}
    VoxelGlass voxels_;
    O options_;
};

/// Glass method "multi".
using MultiGlass = VoxelGlassMethod<MultiGlassOptions, false>;
/// Glass method "two-surface".
using TwoSurfaceGlass = VoxelGlassMethod<TwoSurfaceGlassOptions, true>;
extern template class VoxelGlassMethod<MultiGlassOptions, false>; // render/voxel_glass.cpp
extern template class VoxelGlassMethod<TwoSurfaceGlassOptions, true>;

} // namespace voxfx
