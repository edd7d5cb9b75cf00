// voxfx — screen-space ambient occlusion on the G-buffer (internal): ground-truth ambient occlusion
// (GTAO) of Jimenez, Wu, Pesce and Jarabo, "Practical Real-Time Strategies for Accurate Indirect
// Occlusion" (SIGGRAPH 2016 course; Activision tech. report ATVI-TR-16-01), sections 4 and 5: the
// cosine-weighted visible part of the hemisphere integrated exactly per slice between two horizons
// found by marching the depth buffer, slices rotated and samples offset by a 4x4 interleaved
// pattern that a depth-aware blur removes; computed at half resolution and brought back by a
// bilateral (depth- and normal-aware) upsample. The alternative to the field method of
// voxfx/ambient_occlusion.hpp (cone tracing a distance field): the same quantity, at a fixed cost
// per pixel, blind to what the camera does not see.
//
// What it computes, per covered sample p with unit normal n: the fraction of the cosine-weighted
// hemisphere around n along which no occluder lies within `radius` (what AmbientOcclusion::visibility
// approximates), under the screen-space assumption that everything behind the visible surfaces is
// solid (a height field seen from the eye). Per slice (a plane through the eye ray of p, at screen
// angle phi) the horizon angles h1 <= 0 <= h2 from the view vector v are the highest directions
// towards samples within the radius (clamped to the tangent plane, h in [gamma - pi/2, gamma + pi/2]
// with gamma the angle of n's projection onto the slice), and the slice's visible part is
// (paper, eq. 10)   a(h1, h2) = 1/4 sum_{h in {h1, h2}} (cos gamma + 2 h sin gamma - cos(2 h - gamma)).
// The visibility is sum |n_slice| a(h1, h2) / sum |n_slice| a(gamma - pi/2, gamma + pi/2) over the
// slices: the ratio to the same sum with nothing occluded (which tends to 1 as slices are added),
// so that an unoccluded sample is exactly 1 (a flat floor does not darken, tested).
//
// Beyond the paper: the horizon is interpolated up to the radius between the last sample within it
// and the first beyond (where the segment between them crosses the sphere), so a wall occludes as
// far as the radius and not as far as the last sample happened to fall; the blur and the upsample
// follow links between neighbouring pixels on one smooth surface (a binary bilateral filter); and
// the G-buffer entries skip the horizon search of a working pixel that it could not raise (no
// occluder within twice the radius in view depth within its reach on screen, but coplanar points of
// its own flat mesh: ScreenSpaceOcclusionOptions::flatMeshes), which is most of them (the tree demo's
// frame: 72 % of the covered working pixels), with the search's output bit for bit.
//
// Accuracy (tests/test_screen_space_ao.cpp, at the default 4 steps per side): a floor meeting a
// wall, against the closed form, mean error 0.011 within the radius (max 0.094, next to the crease
// at half resolution; 5 steps: 0.007 and 0.090); the tree and bunny demos, where something is
// occluded, 0.06-0.08 from the field method and 0.07 from counted rays (5 steps: 0.05-0.07 and
// 0.06; the field method: 0.03-0.04). What it misses: occluders outside the image or
// hidden behind nearer surfaces, and the far side of thin objects (a branch counts as a solid slab
// behind it): screen-space methods see only the depth buffer.
//
// Thread-safety: pure functions; rows run in parallel (parallelFor) and the output does not depend
// on the thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/math.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::detail {

struct TriangleBasis; // render/render_cache.hpp

/// Per triangle of the flattened scene, what the passes that test triangles at random per sample
/// read (the anti-aliasing's marking of cells, the screen-space occlusion's downsample): its unit face
/// normal (TriangleBasis::normal) and, in `mesh`, its mesh (SceneGeometry::triangleMesh, kTagMesh
/// bits), kTagOccludes where its material is opaque (an index past the materials: not) and kTagFlat
/// where its shading normal is its face normal to within about half a degree: each of its three
/// corner normals within kTagFlatCos of the face normal (either side; a leaf, a facet of a
/// flat-shaded mesh or of a finely tessellated one), so that a pass needing the shading normal takes
/// the face normal without reading the 84-byte basis. 16 bytes a triangle (render/shading.hpp
/// triangleTags; kept in the render cache).
struct TriangleTag {
    Vec3f normal;
    uint32_t mesh = 0;
};
inline constexpr uint32_t kTagOccludes = 0x80000000u, kTagFlat = 0x40000000u, kTagMesh = 0x3fffffffu;
/// The bits two triangles of one mesh and one material share.
inline constexpr uint32_t kTagSurface = kTagMesh | kTagOccludes;
/// The cosine within which a flat triangle's corner normals lie of its face normal: 0.01 radians
/// (0.57 degrees). The forest's leaves: about three quarters of its triangles (the rest trunks and
/// branches); the occlusion moves by at most a few thousandths (tests/test_screen_space_ao.cpp).
inline constexpr float kTagFlatCos = 1 - 5e-5f;

struct ScreenSpaceOcclusionOptions {
    /// Occluders farther than this from a point do not occlude it (world units, > 0): the radius the
    /// field method uses (RenderOptions::occlusionRadius, or fieldOcclusionSetup's default).
    double radius = 0;
    /// Slices per pixel (1..16). The 4x4 pattern rotates them by sixteenths of pi / directions, so
    /// after the blur every pixel averages 16 x directions slice angles spread evenly over pi.
    int directions = 2;
    /// Horizon samples per side of a slice (1..32), spaced as the 1.5th power of their index out to
    /// 1.2 radii on screen (denser near the pixel, where contact occlusion is), offset per pixel by
    /// the pattern; the horizon is interpolated to the radius between the last sample within it and
    /// the first beyond. Directions x steps = 2 x 4: 16 samples per working pixel (5 steps, the
    /// default before 2026-12-08: 20, a fifth more search for errors about a tenth smaller; see the
    /// accuracy figures above).
    int steps = 4;
    /// Compute on a 2x2-downsampled buffer (per block the mean of its samples where they show one
    /// smooth surface, else its sample nearest the eye) and upsample bilaterally: about a third of
    /// the cost. False: one evaluation per sample (the quality option).
    bool halfResolution = true;
    /// Samples less than this angle (radians, 0..pi/4) above the tangent plane are ignored: a
    /// coarsely tessellated curved surface must not occlude itself where its flat facets rise above
    /// the plane of the interpolated normal. Surfaces meeting at a larger angle occlude fully.
    double bias = 0.1;
    /// Walk the four sides of two slices of two pixels at once in SIMD lanes (builds with AVX2, as
    /// x86-64-v3; elsewhere always one side at a time). False: one side at a time, the scalar
    /// reference the tests compare it with; both give the same output bit for bit.
    bool vectorWalk = true;
    /// The G-buffer entries (whose samples know their mesh), at half resolution: per mesh index of the
    /// geometry, nonzero where the mesh is flat (FieldOcclusionSetup::flatMeshes). A working pixel
    /// skips its horizon search, and is 1, where the search could find nothing: where no occluding
    /// sample within its reach on screen lies within twice the radius of it in view depth (the
    /// nearest an occluder or a crossing of the sphere can be), occluders of its own flat mesh
    /// excepted when it lies on one (coplanar points never rise above its tangent plane by the bias
    /// angle). Checked per 8x8 tile of working pixels against the depth ranges of the tiles in reach.
    /// The output is the search's bit for bit (tested); empty: no skipping.
    std::span<const uint8_t> flatMeshes;
};

/// Visibility (1 = unoccluded, cosine-weighted, as AmbientOcclusion::visibility) per sample of a
/// width x height buffer (row-major, y up, as the G-buffer), from world-space positions and unit
/// shading normals (turned towards the eye, as surfaceAt gives them) per sample. `covered[i]` 0
/// marks background samples (visibility 1; position and normal unused). `occluder` (empty: every
/// covered sample) marks the covered samples that occlude others (the renderer's rule: opaque
/// materials; see gatherSurfaces); the others only receive. `camera` is the G-buffer's perspective
/// Frame (width x height columns). Deterministic: no random numbers (a fixed 4x4 pattern), the same
/// output for every thread count. Cost at the defaults, 1280 x 720 (the tree demo, one core of the
/// project's 2.1 GHz machine, bench/bench_ssao.cpp, with the scalar horizon search of before
/// vectorWalk): 66 ms of CPU with fresh buffers, 43 ms with a kept ScreenSpaceOcclusionScratch (the
/// field method: 73 ms to build, 323 ms of lookups); full resolution about 3x. The SIMD search took
/// about a quarter off the occlusion's share of a renderer's frame (BENCHMARKS.md, #34). Rows run in
/// parallel. Throws voxfx::Error for a camera that is not perspective or not width x height, spans of other
/// sizes, or options out of range.
std::vector<float> screenSpaceOcclusion(const Frame& camera, int64_t width, int64_t height,
                                        std::span<const Vec3f> position, std::span<const Vec3f> normal,
                                        std::span<const uint8_t> covered,
                                        const ScreenSpaceOcclusionOptions& options,
                                        std::span<const uint8_t> occluder = {});

/// A sample as the horizon search reads it: position and flags in 16 bytes, one cache line per
/// sample (internal; here so that a scratch can hold them).
struct alignas(16) ScreenSpaceSample {
    Vec3f position;
    uint32_t flags = 0;
};
/// A sample as the horizon search reads it, in 8 bytes: its depth along the camera's forward axis
/// (0: it does not occlude) and its offset from its pixel's central ray in 1/8192ths of a pixel, so
/// that the rows within the search's reach stay in a core's cache (internal).
struct alignas(8) ScreenSpaceWalkSample {
    float depth = 0;
    int16_t offsetX = 0, offsetY = 0;
};
/// The buffers screenSpaceOcclusion works in (about 16 bytes per sample at half resolution, 48 at
/// full). A caller that computes occlusion frame after frame keeps one, so that the memory is
/// reused: fresh buffers cost a page fault per 4 KiB touched (on this project's virtual machines
/// about a third of the call; bench/bench_ssao.cpp measures both). Nothing carries over between
/// calls but the allocations; not for concurrent calls.
struct ScreenSpaceOcclusionScratch {
    std::vector<ScreenSpaceSample> samples;
    std::vector<ScreenSpaceWalkSample> walk;
    std::vector<Vec3f> normals;
    std::vector<uint8_t> links;
    std::vector<float> raw, across, smooth;
    std::vector<int32_t> meshes; ///< per working pixel: its mesh (-1: none or several); flatMeshes only
    struct Tile {
        float occluderMin = 0, occluderMax = 0; ///< occluders' view depths
        int32_t occluderMesh = -1;              ///< -1: no occluder, -2: several meshes, else the one
        int32_t skipMesh = -1;                  ///< its pixels of this flat mesh skip the search
        uint8_t skipAll = 0;                    ///< all its pixels skip the search
    };
    std::vector<Tile> tiles;
};
/// screenSpaceOcclusion into `visibility` (width x height entries, every one written), working in
/// `scratch`. Throws voxfx::Error as below, and for a `visibility` of another size.
void screenSpaceOcclusion(const Frame& camera, int64_t width, int64_t height, std::span<const Vec3f> position,
                          std::span<const Vec3f> normal, std::span<const uint8_t> covered,
                          const ScreenSpaceOcclusionOptions& options, std::span<const uint8_t> occluder,
                          std::span<float> visibility, ScreenSpaceOcclusionScratch& scratch);

/// The renderer's entry: screenSpaceOcclusion over the cells of `gbuffer` (adaptive x adaptive
/// samples each; 1: every sample), one sample per cell, the one the shading pass shades there
/// ((adaptive / 2, adaptive / 2) of the cell), into `visibility` (one per cell, row-major, y up).
/// Reads the G-buffer itself rather than gathered buffers: a cell's position from its depth, its
/// normals from its triangle's basis (`bases`, triangleBases of `geometry`) only where a step needs
/// them (one shading normal per 2x2 block; face normals where the downsample tests for one surface
/// and where the upsample cannot interpolate), so at half resolution it evaluates about a quarter
/// of the shading normals; the same method, and within 0.0001 on average the same result, as the
/// overload above on gatherSurfaces' buffers (tests/test_screen_space_ao.cpp runs both). A triangle occludes
/// where opaqueMaterial[its material] is nonzero (an index past it does not). Throws voxfx::Error as the
/// overload above, and for a G-buffer that is not whole cells, bases of another count or `visibility` of
/// another size. `tags`: triangleTags of the geometry, bases and opaqueMaterial where the caller keeps
/// them (the renderer, in its cache); empty: made here.
void screenSpaceOcclusion(const GBuffer& gbuffer, const SceneGeometry& geometry,
                          std::span<const TriangleBasis> bases, std::span<const uint8_t> opaqueMaterial,
                          int adaptive, const ScreenSpaceOcclusionOptions& options,
                          std::span<float> visibility, ScreenSpaceOcclusionScratch& scratch,
                          std::span<const TriangleTag> tags = {});

/// The renderer's entry in two halves, so that the last step, the bilateral upsample to the cells,
/// runs where the shading pass has each cell's surface point already (position and face normal: no
/// second reconstruction from the G-buffer, no second visit to the triangle): the constructor runs
/// the rest of screenSpaceOcclusion's G-buffer entry (downsample, horizon search, blur; without
/// halfResolution, every cell), `at` gives one covered cell's visibility. The same method and
/// arithmetic as that entry, which upsamples through `at`'s code with the position from the depth
/// and the face normal of its cell. The object reads its arguments and `scratch` until it is
/// destroyed; `at` is thread-safe. `tags` as the G-buffer entry's. Throws voxfx::Error as the
/// G-buffer entry does.
class CellOcclusion {
public:
    CellOcclusion(const GBuffer& gbuffer, const SceneGeometry& geometry, std::span<const TriangleBasis> bases,
                  std::span<const uint8_t> opaqueMaterial, int adaptive,
                  const ScreenSpaceOcclusionOptions& options, ScreenSpaceOcclusionScratch& scratch,
                  std::span<const TriangleTag> tags = {});
    ~CellOcclusion();
    CellOcclusion(const CellOcclusion&) = delete;
    CellOcclusion& operator=(const CellOcclusion&) = delete;
    int64_t width() const;  ///< cells
    int64_t height() const; ///< cells
    /// The visibility of covered cell (cx, cy) whose sample (the shading pass's) lies at `position`
    /// with face normal `faceNormal` turned towards the eye (surfaceFromBasis' geometricNormal).
    float at(int64_t cx, int64_t cy, const Vec3f& position, const Vec3f& faceNormal) const;

    struct Impl; ///< its state (screen_space_ao.cpp)

private:
    std::unique_ptr<Impl> impl_;
};

/// The G-buffer's surface points as the plain buffers screenSpaceOcclusion reads: per sample the
/// position and normal of surfaceAt, covered, and occluder = the triangle's material is opaque
/// (Material::isOpaque, the field method's rule; a material index past `materials` does not occlude).
struct SurfaceBuffers {
    std::vector<Vec3f> position, normal;
    std::vector<uint8_t> covered, occluder;
};
SurfaceBuffers gatherSurfaces(const GBuffer& gbuffer, const SceneGeometry& geometry,
                              std::span<const Material> materials);

/// What the renderer's occlusion pass (render/renderer.cpp occlusionPass, as of this file) derives
/// from the scene for the field method, in one place so that the screen-space method gets the same
/// radius: the opaque triangles' indices, the region (the non-flat opaque meshes' bounds, all of
/// them when every one is flat: a flat mesh never occludes itself), the radius (`radius` when > 0,
/// else a tenth of the median diagonal of those meshes) and the field's resolution (`resolution`,
/// at least 4 cells per radius, clamped to 8..2048). radius 0 when nothing occludes.
struct FieldOcclusionSetup {
    /// Per mesh index: 1 where every vertex of every triangle of the mesh lies on one plane (to 1e-6
    /// of its size; ScreenSpaceOcclusionOptions::flatMeshes).
    std::vector<uint8_t> flatMeshes;
    std::vector<uint32_t> indices;
    Box3d region;
    double radius = 0;
    int64_t resolution = 0;
};
FieldOcclusionSetup fieldOcclusionSetup(const SceneGeometry& geometry, std::span<const Material> materials,
                                        std::size_t meshCount, double radius, int64_t resolution);

} // namespace voxfx::detail
