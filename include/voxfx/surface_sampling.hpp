// voxfx — random points on and near a triangle mesh, as learning pipelines prepare their data
// (DeepSDF, Park et al. 2019, §5: points near the surface with their signed distances; Occupancy
// Networks, Mescheder et al. 2019, §4: points in the bounding box with inside labels).
//
// EXPERIMENTAL until #35 closes.
//
// Surface samples are area-weighted: triangle t is picked with probability area(t) / total area
// (Walker's alias table of the areas, built by Vose's method in double: O(1) per sample), then a
// point uniformly inside it (barycentric weights (1 - sqrt(u), sqrt(u) (1 - v), sqrt(u) v), Osada
// et al. 2002, §4.2), so the points are uniform over the surface. Triangles of zero area are never
// picked.
//
// Determinism: sample i draws its random numbers from a counter-based generator (SplitMix64's
// mixing function over (seed, i, k)), not from a sequential stream, so sample i is the same
// whatever the thread count, the chunking, or how many samples are asked for (the first n of a
// call for 2n are the n of a call for n). Near-surface samples use the same surface samples: the
// first samples of sampleNearSurface(n, seed) start from sampleSurface(n, seed)'s points.
//
// Thread-safety: pure functions of their inputs; they use worker threads (`threads`).
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/distance.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

struct SurfaceSampleOptions {
    int threads = 0;              ///< worker threads, 0 = all; results are identical for every value
    Progress* progress = nullptr; ///< polled between chunks of samples; may cancel. Not owned.
};

/// Points on the surface with the face they lie on.
struct SurfaceSamples {
    std::vector<Vec3d> points;   ///< on the triangles of the float vertices, in double
    std::vector<Vec3f> normals;  ///< the unit normal of each point's face (counter-clockwise side)
    std::vector<uint32_t> faces; ///< the triangle each point lies on
};

/// `count` points uniformly distributed over the mesh's surface (see the file comment). Throws
/// voxfx::Error for an invalid mesh (validateMesh), a negative count, or a mesh whose triangles
/// all have zero area. count 0 gives empty arrays. Cost: O(T) for the area table, O(count log T)
/// for the samples, in parallel.
SurfaceSamples sampleSurface(const MeshView& mesh, int64_t count, uint64_t seed,
                             const SurfaceSampleOptions& options = {});

struct NearSurfaceOptions {
    /// Standard deviations (world units, each > 0) of the Gaussian offsets added to surface points:
    /// the near-surface samples cycle through them (sample i uses sigmas[i % size]), as DeepSDF
    /// mixes two. At least one.
    std::vector<double> sigmas{0.01};
    /// The share of the samples drawn uniformly in the mesh's bounding box grown by `boxMargin`
    /// (Occupancy Networks' volume points), in [0, 1]; they are the last ones.
    double uniformFraction = 0;
    /// The box of the uniform samples: the mesh's bounds grown on every side by this fraction of
    /// their longest extent (>= 0).
    double boxMargin = 0.1;
    /// How the sign is decided (voxfx/distance.hpp: parity for closed meshes under Auto).
    SignMethod sign = SignMethod::Auto;
    double windingBeta = 3.0;
    int threads = 0;
    Progress* progress = nullptr;
};

/// Points near the surface with their exact signed distances (negative inside) and inside labels.
struct NearSurfaceSamples {
    std::vector<Vec3d> points;
    std::vector<double> distances; ///< signedDistance(): exact distance, negative inside
    std::vector<uint8_t> inside;   ///< 1 where the sign is negative (-0.0 included: on the surface, inside)
};

/// `count` points: the first count - round(count * uniformFraction) are surface samples
/// (sampleSurface with the same seed) moved by isotropic Gaussian offsets, the rest uniform in the
/// grown bounding box; then their signed distances (signedDistance with options.sign) and inside
/// labels. Throws voxfx::Error as sampleSurface, and for no sigma, a sigma that is not finite and
/// positive, a fraction outside [0, 1], a negative or non-finite margin. Cost: sampling plus the
/// signed distances (voxfx/distance.hpp).
NearSurfaceSamples sampleNearSurface(const MeshView& mesh, int64_t count, uint64_t seed,
                                     const NearSurfaceOptions& options = {});

} // namespace voxfx
