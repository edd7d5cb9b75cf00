// voxfx — voxelization of triangle meshes into slicemaps (ED06 §2, GI08 §4–5).
//
// Every mode is a consumer of the one fragment rasterizer (raster.hpp):
//   Surface             ED06: every centre-sampled fragment sets the bit of the slice its depth
//                       falls in. Faithful to the paper, holes included: a steep triangle yields
//                       one fragment per column, one parallel to the slicing axis none.
//   Conservative        every cell whose closed box the triangle overlaps (26-separating): the
//                       triangle clipped to each touched column prism gives the depth interval.
//                       Exact up to a slack of 1e-9 cell (raster.hpp kConservativeSlack): cells
//                       the triangle touches are never lost to rounding, and cells it misses by
//                       less than 1e-9 of a cell are included (CGAL tests count those).
//   Solid               GI08 parity at cell centres: a cell is inside when an odd number of
//                       surfaces lie in front of its centre along the column. Fragments flip one
//                       bit at their crossing; one prefix-XOR per column finishes.
//   SolidConservative   Solid ∪ Conservative (GI08 §5 (a)).
//   Interior            Solid \ Conservative: strictly interior cells (GI08 §5 (b)).
//
// Parity needs a closed mesh. For open or self-intersecting input choose a robust `fill`:
//   Fill::Parity        exact for closed meshes (the default); self-intersections give the
//                       symmetric difference of the overlapping parts (GI08).
//   Fill::Flood         inside = cells not reachable from the grid border without crossing the
//                       conservative surface (6-connected flood). Seals holes narrower than a cell;
//                       larger holes let the flood in and the interior is lost. Includes the
//                       surface cells (it is a solid-conservative result).
//   Fill::Vote          parity along the three axes, majority per cell. Tolerates a few small
//                       holes and bad triangles (an error must fool two of three axes), costs 3×.
//   Fill::Winding       nonzero winding number from per-column sorted front/back fragments: the
//                       union of overlapping closed parts (needs consistent orientation).
//   Fill::Gwn           generalized winding number |w| >= 0.5 at the cell centre (Jacobson et al.
//                       2013), fast approximation after Barill et al. 2018 (the evaluator of
//                       contains()' winding method, beta 2). Closes holes wider than a cell that
//                       let the flood in; needs orientation consistent within each closed part,
//                       outward or inward (as contains()' winding method); evaluates near boundary
//                       edges, where it is near 0.5, and a few centres per block (voxfx/contains.hpp).
// Thread-safety: calls may run concurrently on shared const meshes (no global state); each call
// spreads its tiles over worker threads (`threads`); results do not depend on their number.
#pragma once

#include <cstdint>
#include <string>

#include "voxfx/device.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/types.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

const char* toString(VoxelizeMode m);
const char* toString(Fill f);
/// Parse a name of kVoxelizeModeNames, kFillNames, kAxisNames, kSlicingNames (any case); throw
/// voxfx::Error listing the allowed names otherwise.
VoxelizeMode parseVoxelizeMode(const std::string& name);
/// True for the modes whose inside a fill decides: Solid, SolidConservative, Interior.
bool needsFill(VoxelizeMode mode);
Fill parseFill(const std::string& name);
Axis parseAxis(const std::string& name);
Slicing parseSlicing(const std::string& name);

/// What voxelize() decided, for front ends to print (VoxelizeOptions::report).
struct VoxelizeReport {
    /// The fill that decided the inside: options.fill, or what Fill::Auto chose (Parity for the
    /// surface modes, whose fill does not matter).
    Fill fill = Fill::Parity;
    /// Fill::Auto with a mode that needs a fill: the mesh's topology, from which it chose.
    bool topologyAnalyzed = false;
    MeshTopology topology;
    /// Why Fill::Auto chose flood, one line without the mesh's name ("not closed (6 boundary, 0
    /// non-manifold, 0 misoriented edges): filled by flood (...)"); empty when it chose parity.
    std::string fillNote;
};

struct VoxelizeOptions {
    VoxelizeMode mode = VoxelizeMode::Solid;
    /// How the inside is decided for Solid, SolidConservative and Interior. Auto costs one pass
    /// over the edges (analyzeTopology, hashing) before the voxelization.
    Fill fill = Fill::Parity;
    /// ED06 local slicing: first records the nearest and farthest fragment of each column, then
    /// spreads the D slices over that range only (orthographic frames only for export).
    Slicing slicing = Slicing::Uniform;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
    /// Polled between tiles; may cancel. Not owned.
    Progress* progress = nullptr;
    /// The rasterizer's parallel scheme (binned tiles or direct atomic writes); same result.
    RasterPath rasterPath = RasterPath::Auto;
    /// Where to run (voxfx/device.hpp): the CPU, the CUDA back end (else the CPU, and a note in
    /// `deviceNote`), or Auto (the GPU when it can take the job). The grid is the same bit for bit.
    /// The GPU runs every mode with the parity fill; the other fills run on the CPU.
    Device device = Device::Cpu;
    /// Receives why a Cuda or Auto request ran on the CPU; cleared when the GPU ran it. Not owned.
    std::string* deviceNote = nullptr;
    /// Receives what was decided (the fill Auto chose, and why). Not owned.
    VoxelizeReport* report = nullptr;
    /// Padding: the cells within this many of every side of an axis-aligned, uniformly sliced
    /// frame stay empty in every mode. Surface cells there (a conservative cell of a face lying on
    /// the fitted bounds) are dropped before the fill, so a flood enters from the border, and the
    /// result is cleared there. 0: no such ring.
    int64_t emptyBorder = 0;
};

/// How to fit an orthographic frame to a mesh. Cells are cubes unless `dims` is given.
///   resolution N: the longest extent of the bounds gets N cells; other axes get
///                 ceil(extent / cell) cells (at least 1); the grid is centred on the bounds.
///   voxelSize S:  cubic cells of edge S; dims = ceil(extent / S), grid centred on the bounds.
///   cube:         with resolution N: N cells along every axis, of the longest extent's size
///                 (cubic), the bounds centred: an N x N x N grid, never stretched.
///   dims (W,H,D): world-axis cell counts (x, y, z), cells fill the bounds exactly (non-cubic).
///   bounds:       box to fit instead of the mesh bounds (e.g. shared by several meshes).
/// Margin: `marginCells` empty cells are added on every side (default 0; cell centres then sit
/// at lo + (i + 0.5) * cell for i = 0..n-1, where lo is the fitted box's lower corner).
struct FitOptions {
    int64_t resolution = 0;
    double voxelSize = 0;
    Vec3i dims{0, 0, 0};
    bool cube = false; ///< with resolution: resolution^3 cubic cells (see above)
    Box3d bounds;      ///< empty = mesh bounds
    int64_t marginCells = 0;
    Axis axis = Axis::Z;
    /// Refuse grids whose dense bits need more memory than is available. Off for sparse and tiled
    /// voxelization (voxfx/sparse_grid.hpp, voxfx/tiled.hpp), which never build the dense grid.
    bool checkDenseMemory = true;
};

/// Fits an orthographic frame to `meshBounds` as described by `options` (exactly one of
/// resolution, voxelSize, dims must be set). Throws voxfx::Error for an empty or flat box with
/// resolution 0, non-positive sizes, or (checkDenseMemory) a grid whose memory would exceed what
/// is available.
Frame fitFrame(const Box3d& meshBounds, const FitOptions& options);

/// The fill voxelize() (and voxelizeTiles, voxelizeSparse) use for `options` in `frame`:
/// options.fill, or for Fill::Auto Parity when the mesh is closed or the mode needs no fill, else
/// Flood (one pass over the edges) where the frame is an axis-aligned, uniformly sliced
/// orthographic grid and Gwn where it is not (perspective, oriented or locally sliced frames:
/// light views). Writes *options.report when given.
Fill resolveFill(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& options);

/// Voxelizes `mesh` into `frame`. Returns the grid (in `frame`, with local slicing applied when
/// requested). Validates the mesh first (voxfx::Error on bad indices or non-finite vertices).
/// Triangles outside the frame are ignored; for parity, geometry in front of the near plane
/// still counts (depth clamping, GI08 §4). Cost: O(triangles + fragments + cells / 64).
VoxelGrid voxelize(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& options = {});

} // namespace voxfx
