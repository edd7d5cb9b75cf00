// voxfx — constructive solid geometry on bit grids and CSG trees of meshes (GI08 §6: union,
// intersection, difference and symmetric difference of solid grids are OR, AND, AND-NOT, XOR).
//
// Grid CSG works on whole words and keeps the slicemap invariant (padding bits stay zero): every
// operation is a function of the two operands' bits, and all four map (0, 0) to 0.
//
// Mesh CSG: an expression names meshes and nests operations; every mesh is voxelized as a solid
// into one frame fitted to the union of all their bounds, then the tree is evaluated bottom-up.
// Two syntaxes, picked by the first non-blank character:
//   functional   difference(bunny.off, union(a.stl, "b c.stl"))
//                  op    := union | intersection | difference | xor   (also: or, and, minus, sub)
//                  arg   := op '(' arg (',' arg)* ')' | path | '"' path '"'
//                  paths without quotes may not contain ',', '(', ')' or '"'; blanks around an
//                  argument are ignored. A name followed by '(' is an operation.
//   JSON         {"op": "difference", "args": ["bunny.off", {"op": "union", "args": ["a.stl", "b.stl"]}]}
//                  a node is a string (a mesh path) or an object with "op" and "args".
// n-ary operations fold left: difference(a, b, c) = (a - b) - c; union/intersection/xor of one
// argument is that argument. The expression API (CsgNode and below) is experimental: it may
// change until the issue closes; the grid operations are stable.
// Thread-safety: calls may run concurrently (no global state) as long as no call writes a grid
// another uses; the grid operations and voxelizeCsg use worker threads internally, the
// expression functions run on the calling thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

enum class CsgOp : uint8_t { Union, Intersection, Difference, Xor };
inline constexpr EnumName<CsgOp> kCsgOpNames[] = {{"union", CsgOp::Union},
                                                  {"intersection", CsgOp::Intersection},
                                                  {"difference", CsgOp::Difference},
                                                  {"xor", CsgOp::Xor},
                                                  {"or", CsgOp::Union, true},
                                                  {"and", CsgOp::Intersection, true},
                                                  {"minus", CsgOp::Difference, true},
                                                  {"sub", CsgOp::Difference, true},
                                                  {"symmetric-difference", CsgOp::Xor, true}};

const char* toString(CsgOp op);
/// "union", "intersection", "difference", "xor" (and the aliases or, and, minus, sub);
/// throws voxfx::Error listing the allowed names otherwise.
CsgOp parseCsgOp(const std::string& name);

/// a = a op b, in place, word by word (one pass over both grids, parallel). Throws voxfx::Error
/// when the dimensions differ. Cost: ~ one memory copy of the grid.
void csgInPlace(BitGrid& a, const BitGrid& b, CsgOp op);
/// a op b as a new grid (same rules as csgInPlace).
BitGrid csg(const BitGrid& a, const BitGrid& b, CsgOp op);
/// a op b into a caller-owned grid, reallocated only when its size differs (for repeated
/// operations without allocation). `out` may be `a` (then this is csgInPlace) but not `b`.
void csg(const BitGrid& a, const BitGrid& b, CsgOp op, BitGrid& out);
/// CSG of two grids that must lie in the same frame (Frame::sameGrid: same camera, box, sizes and
/// slicing); otherwise throws voxfx::Error saying how the frames differ. The result keeps a's frame.
VoxelGrid csg(const VoxelGrid& a, const VoxelGrid& b, CsgOp op);
/// a op b on the GPU (voxfx/device.hpp), bit for bit the CPU's: grids of one size (voxfx::Error
/// otherwise); voxfx::Error when no GPU can be used.
CudaGrid csg(const CudaGrid& a, const CudaGrid& b, CsgOp op);

/// A node of a CSG expression: a mesh (leaf) or an operation over one or more nodes.
struct CsgNode {
    bool isMesh = true;
    std::string mesh;          ///< leaf: the mesh path, as written
    CsgOp op = CsgOp::Union;   ///< operation node: the operation
    std::vector<CsgNode> args; ///< operation node: its arguments (at least one)
};

/// Parses either syntax (see the file comment; JSON is read by nlohmann-json). Throws
/// voxfx::Error on malformed text: the message gives the 1-based column where parsing failed
/// and what was expected there, or for a well-formed JSON document that is no CSG tree, the
/// JSON pointer of the offending node ("at /args/1/op: unknown operation ...").
CsgNode parseCsgExpression(std::string_view text);
/// The canonical functional form, e.g. "difference(a.off, union(b.stl, c.stl))" (paths with
/// special characters are quoted).
std::string toString(const CsgNode& node);
/// The distinct mesh paths of an expression, in order of first appearance.
std::vector<std::string> csgMeshes(const CsgNode& node);

/// Evaluates an expression bottom-up: `leaf(path)` returns the solid grid of one mesh (all in
/// one frame and with equal dimensions: voxfx::Error otherwise). Each distinct path is asked for
/// once per occurrence; at most (tree depth + 1) grids are alive at a time.
BitGrid evaluateCsg(const CsgNode& node, const std::function<BitGrid(const std::string&)>& leaf);

/// A mesh of a CSG expression and how its inside is decided.
struct CsgMesh {
    std::string path; ///< as named in the expression
    MeshView mesh;    ///< not owned
    Fill fill = Fill::Parity;
    VoxelizeReport* report = nullptr; ///< receives what voxelize() decided for this mesh; not owned
};

/// Voxelizes every mesh of `node` as a solid (VoxelizeMode::Solid with each mesh's fill; other
/// fields of `voxelize` apply to all) in one orthographic frame fitted by `fit` to the union of
/// all mesh bounds (or to fit.bounds when set), and evaluates the expression. Throws
/// voxfx::Error when a path of the expression is missing from `meshes`.
/// Cost: one voxelization per mesh occurrence plus one pass per operation.
VoxelGrid voxelizeCsg(const CsgNode& node, const std::vector<CsgMesh>& meshes, const FitOptions& fit,
                      const VoxelizeOptions& voxelize = {});

} // namespace voxfx
