// voxfx demo scenes — the procedural scenes `voxfx demo` renders (and the tests and benchmarks that
// render them), built in memory through the public API (writeGltf saves them). Not part of the
// library: the CLI, the tests and the benchmarks link them (target voxfx_demo_scenes).
//
//   tree    a procedural tree: an opaque trunk with branches, thousands of leaf quads in colour
//           groups (partial occluders), a ground plane that only receives, a sun (directional).
//   bunny   the Stanford bunny (bunny00.off) under a canopy of leaves, lit by a spot light and a low
//           sun (directional).
//   cgal    meshes from the CGAL data set (elephant, armadillo, cactus) under a leafy pergola lit by
//           a point light and a directional one.
//   glass   glass objects (the bunny, a torus knot, two coloured glasses, a ruby bunny inside a glass
//           ball) over a checkered ground.
//   forest  64 trees of the tree scene's kind (1,000 leaf quads each: 128,000 leaf triangles) on a
//           jittered lattice over a ground, the tree scene's sun, a camera over the lattice: the
//           scale at which tracing every leaf costs what the voxel lookups save (issue #34). Not
//           in `voxfx demo`'s default list (a frame takes seconds); made when named.
// Every scene has one camera (glass: a second one close to the ball). Generation is deterministic
// (fixed seeds).
//
// Thread-safety: makeDemoScene may run concurrently (it only reads mesh files and builds a new
// Scene); it runs on the calling thread.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "voxfx/mesh.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::demo {

struct TreeOptions {
    int leaves = 3000;        ///< leaf quads (2 triangles each)
    int colourGroups = 3;     ///< leaf colour groups (1..4): different shadow channels
    double leafSize = 0.15;   ///< leaf edge length (the tree is about 4 units tall)
    float leafOpacity = 0.6f; ///< Material::opacity of the leaves
    float leafTransmission = 0.6f;
    int trunkSides = 16;
    bool ground = true;
    uint64_t seed = 1;
};

Scene makeTreeScene(const TreeOptions& options = {});

struct ForestOptions {
    int trees = 64;           ///< on a square lattice of ceil(sqrt(trees)) columns
    int leavesPerTree = 1000; ///< leaf quads per tree (2 triangles each)
    int colourGroups = 3;     ///< leaf colour groups (1..4), as TreeOptions
    double leafSize = 0.15;   ///< leaf edge length before the tree's scale (0.8..1.25)
    float leafOpacity = 0.6f; ///< Material::opacity of the leaves
    float leafTransmission = 0.6f;
    int trunkSides = 12;
    double spacing = 3.6; ///< lattice spacing (a tree's crown is about 3.5 units across)
    uint64_t seed = 7;
};

/// A forest: `trees` procedural trees (the tree scene's generator, each with its own seed derived
/// from `seed` and its index, moved, scaled and turned at random) sharing one trunk mesh and one
/// leaf mesh per colour group, a receive-only ground, a sun and one camera framing the lattice.
/// The trees' places and shapes do not depend on leavesPerTree, so forests of 10x the leaves
/// differ only in leaf density. Deterministic. Throws voxfx::Error for trees < 1 or a negative
/// leaf count.
Scene makeForestScene(const ForestOptions& options = {});

/// Triangles of the meshes that cast shadows and let light through (the leaves of the demo scenes).
int64_t leafTriangleCount(const Scene& scene);

/// The bunny (meshesDir/bunny00.off, scaled to about 1.2 units) under a leaf canopy. Throws
/// voxfx::Error when the mesh cannot be loaded.
Scene makeBunnyScene(const std::string& meshesDir, int leaves = 4000, uint64_t seed = 2);

/// Elephant, armadillo and cactus from meshesDir under a pergola of leaves. Meshes that are
/// missing are skipped (at least one must load, else voxfx::Error).
Scene makeCgalScene(const std::string& meshesDir, int leaves = 5000, uint64_t seed = 3);

/// Glass (no lights: the default sun and sky): a glass bunny (meshesDir/bunny00.off), a
/// self-occluding green glass torus knot, a block of amber and blue glass and a ruby bunny inside a
/// clear glass ball (nested glass, CHANG fig. 3) over a checkered ground.
Scene makeGlassScene(const std::string& meshesDir);

/// The mesh folder/file (loadMesh), or nullopt when the file does not exist.
std::optional<Mesh> loadDemoMesh(const std::string& folder, const std::string& file);

/// Appends the axis-aligned box [lo, hi] to m: 8 corners, 12 outward-facing triangles.
void appendBox(Mesh& m, const Vec3d& lo, const Vec3d& hi);

/// "tree", "bunny", "cgal", "glass": the scenes `voxfx demo` renders by default.
std::vector<std::string> demoSceneNames();
/// "forest": scenes made by name only (each frame takes seconds).
std::vector<std::string> largeDemoSceneNames();
/// makeTreeScene / makeBunnyScene / makeCgalScene / makeGlassScene / makeForestScene (default
/// options) by name; voxfx::Error for an unknown name.
Scene makeDemoScene(const std::string& name, const std::string& meshesDir);

} // namespace voxfx::demo
