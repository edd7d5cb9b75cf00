// voxfx — the volume ray-casting pass (internal): the objects of the scene's VolumeScene composited
// over the shaded G-buffer (Bornik et al. §3): volumes, opaque and translucent objects whose shapes
// are Booleans, and meshes of blended materials (the G-buffer draws only the other plain meshes).
#pragma once

#include <vector>

#include "render/frame_state.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/segment_walker.hpp"

namespace voxfx::detail {

/// Camera ray casting over fragment lists: the boundary triangles of the scene's volume scene are
/// rasterized into fragment lists over the camera frame; each pixel walks its list front to back up
/// to the G-buffer's depth. Where an opaque or translucent object's inside flag changes, the ray
/// crosses its visible surface (ObjectSurfaceHit): it is shaded like a mesh of the object's colour
/// (Blinn–Phong, shadows) and composited with α = 1 (opaque: the walk stops) or the object's
/// opacity. Segments inside volume objects are sampled at their ends and at steps of
/// `options.volumeStep` voxel spacings (the smallest spacing of the finest volume the segment is
/// inside: each volume at its own) from a start jittered per pixel (sampleJitter, so no
/// rings where equal steps from each segment's start would draw them) and composited front to back:
/// each interval of length dl between two samples has the pre-integrated extinction σ of the values
/// at its ends (PreintegratedTransfer; opacity 1 - exp(-σ dl)), its colour = pre-integrated transfer
/// colour × (ambient + Σ lights irradiance × shadow visibility / π), the light taken at the
/// interval's opacity-weighted depth (its middle when thin, 1/σ behind its start when dense) and the
/// shadow looked up one step towards the light (with that direction as the lookup's normal), under
/// deep shadows times the transmittance of the volumes over that step and the map's offsets (the
/// medium the lookup leaves out, at the smaller extinction of its two ends: a uniform slab is
/// Beer–Lambert, a dense layer does not shadow its own front); the map's lookup itself is read,
/// trilinearly, from a grid of the same lookups at the volume's voxel corners built once per (volume,
/// light) and kept in frame.cache (render/volume_light_grid.hpp; the first frame builds it); a piece
/// inside one volume whose shape is its box takes the whole term (irradiance x lookup x own
/// transmittance) from the pre-lit volume, the same product made at the voxel corners and
/// interpolated (volumePrelit; the own transmittance's fall across a dense front is then blurred
/// by a voxel, BENCHMARKS.md "frames-dsm7"). The walk
/// stops when the accumulated opacity reaches 0.99 inside a volume (the light it would still have
/// let through taken as that of the piece it stops at) or 0.999 at a surface, and the result is
/// blended over frame.shaded
/// (row-major, y up). The meshes of blended materials (Material::blend), which the G-buffer leaves
/// out, are walked here too, as translucent objects shaded with their own material. With adaptive
/// anti-aliasing (frame.adaptive > 1) the samples the passes before shaded are cast, then the cells
/// shaded once whose samples' rays cross different faces of the volume scene, or whose composited
/// light differs from a neighbour's, are shaded at every sample (frame.refined; with refinement, where
/// the volumes gave nothing in the cell and the eight around it, a box's edge in air, each sample
/// takes the light behind without a walk). With
/// options.volumeRefinement > 0 the cells shaded once are cast on a coarse lattice (cx and cy
/// multiples of 4) first and the cells between, level by level (spacing 2, then 1), interpolated
/// from the levels before where no edge lies between, else cast (adaptive image-space refinement,
/// RenderOptions::volumeRefinement; the count in frame.result). Records the
/// number of volume samples taken in frame.result. Nothing happens when the scene has neither volume
/// scene objects nor blended meshes.
void compositeVolumes(FrameState& frame);

/// Whether the pass lights a piece inside one box-shaped volume only from the pre-lit volume (the
/// light's irradiance x the deep shadow map's lookup x the volume's own transmittance over the
/// lookup's step, made once per (volume, light) at the voxel corners and interpolated; on by
/// default), or per piece (tests compare the two; the switch is process-wide, not for renders in
/// flight).
bool volumePrelit();
void setVolumePrelit(bool on);

/// A crossing of an opaque or translucent object's boundary along a camera ray.
struct ObjectSurfaceHit {
    double depth = 0;      ///< frame depth (the ray's point is eye + (pixel's depth-1 point - eye) * depth)
    uint32_t object = 0;   ///< index into VolumeScene::objects
    uint32_t triangle = 0; ///< the triangle of the flattened leaves (lowest index of those at this depth)
    bool entering = false; ///< the ray enters the object's shape here
    Vec3d position;
    /// Unit geometric normal pointing out of the object's shape (a subtracted leaf's triangle gets
    /// its normal reversed).
    Vec3d outwardNormal;
};

/// What the pass needs of a volume scene besides its fragment lists: the flattened leaves and,
/// per object, which leaves its shape uses.
struct ObjectSurfaces {
    explicit ObjectSurfaces(const VolumeScene& scene);
    /// The hit of the surface the walker reported at depth z (object o, entering) in column
    /// `fragments` of pixel (x, y) of `frame`.
    ObjectSurfaceHit hit(const Frame& frame, int64_t x, int64_t y, std::span<const ListFragment> fragments,
                         double z, std::size_t o, bool entering) const;
    /// Unit shading normal at the hit (vertex normals averaged over the leaf, the face normal across
    /// creases sharper than 40 degrees), on the side of `facing`.
    Vec3d shadingNormal(const ObjectSurfaceHit& h, const Vec3d& facing) const;

    const VolumeScene* scene;
    FlatLeaves flat;
    std::vector<Vec3d> vertexNormals;               ///< area-weighted, per flat.mesh vertex
    std::vector<std::vector<uint8_t>> objectLeaves; ///< per object, per leaf: used by its shape
};

/// For every pixel of `frame` (row-major, y up), the surfaces of opaque and translucent objects its
/// ray crosses beyond the near plane, nearest first, up to and including the first opaque one: the
/// surfaces compositeVolumes composites (tests compare them with exact inside tests).
std::vector<std::vector<ObjectSurfaceHit>> objectSurfaceHits(const VolumeScene& scene, const Frame& frame);

} // namespace voxfx::detail
