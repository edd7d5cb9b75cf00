// voxfx — a Frame maps world space to a grid of columns and slices (ED06 §2).
//
// A frame is a camera whose image plane holds W x H *columns* and whose depth range is split
// into D *slices*; cell (x, y, s) is the part of column (x, y) between slice boundaries s and s+1.
//
// Grid coordinates (what the rasterizer sees) are (gx, gy, depth):
//   - gx, gy in column units: column x covers [x, x+1), its centre is x + 0.5;
//   - orthographic frames: depth in slice units of the uniform slicing, slice s covers [s, s+1)
//     and its centre is s + 0.5, so cell centres sit at half-integer grid coordinates;
//   - perspective frames: depth is the world distance along the view direction (not z-buffer
//     depth), so that uniform slicing is uniform in real distance (ED06 §2).
// Mesh vertices (floats) go through Projection::gridFromVertex, which puts a vertex on a side of
// an axis-aligned orthographic box exactly on the grid's side (0 or W, H, D).
// Slicing maps a column's depth to a slice coordinate: slice = (depth - near_c) * scale_c, with
// one (near, scale) for the whole frame (uniform) or one per column (local, ED06 fig. 2).
//
// Orthographic axis convention: slices run along `axis`; columns run along the next two axes in
// cyclic order, so the grid is right-handed: axis Z -> columns (x, y); axis X -> columns (y, z);
// axis Y -> columns (z, x).
//
// Oriented orthographic frames (Frame::orthographic with a basis) tile a box given in the local
// coordinates (p . right, p . up, p . forward) of a right-handed orthonormal basis: columns run
// along right and up, slices along forward (axis() is Z). Directional light views use them, so no
// geometry is rotated into an axis-aligned copy. For such a frame box() is the *local* box and
// cellSize() the cell size along (right, up, forward).
//
// Kernels (the rasterizer, its consumers, a future CUDA back end) see a frame through FrameView:
// a trivially copyable value (projection, W, H, D, the uniform slicing and a pointer to the
// local slicing table) with no allocation, exceptions or I/O in its member functions.
//
// Thread-safety: a Frame is a value. Its const members (including view()) may be called from any
// number of threads at once; setLocalSlicing / setUniformSlicing / assignment must not run
// concurrently with any other use of the same Frame, and they invalidate the table pointer of
// earlier views. FrameView is read-only and may be shared freely while its Frame lives unchanged.
#pragma once

#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

enum class Axis : uint8_t { X = 0, Y = 1, Z = 2 };
inline constexpr EnumName<Axis> kAxisNames[] = {{"x", Axis::X}, {"y", Axis::Y}, {"z", Axis::Z}};

/// World axis (0, 1, 2) of the grid's column-x, column-y and slice directions for an orthographic
/// frame sliced along `a`.
VOXFX_HOSTDEV constexpr int columnXAxis(Axis a) { return (int(a) + 1) % 3; }
VOXFX_HOSTDEV constexpr int columnYAxis(Axis a) { return (int(a) + 2) % 3; }
VOXFX_HOSTDEV constexpr int sliceAxis(Axis a) { return int(a); }

const char* toString(Axis a);
const char* toString(Slicing s);

/// Depth-to-slice map of one column: slice coordinate = (depth - near) * scale.
struct DepthToSlice {
    double near = 0;
    double scale = 1;
    VOXFX_HOSTDEV double operator()(double depth) const { return (depth - near) * scale; }
};

/// World -> grid coordinates of a frame (see the file comment), as plain data for kernels.
///   orthographic: grid = ((p[axisX] - origin[axisX]) * scale.x, (p[axisY] - origin[axisY]) * scale.y,
///                         (p[axisS] - origin[axisS]) * scale.z)
///   oriented orthographic: q = p - origin (the world corner of the local box),
///                 grid = ((q . right) * scale.x, (q . up) * scale.y, (q . forward) * scale.z)
///   perspective:  camera coordinates c = ((p - eye) . right, (p - eye) . up, (p - eye) . forward),
///                 grid = (imageX(c.x, c.z), imageY(c.y, c.z), c.z)
/// The rasterizer uses exactly these functions, so its coordinates and Frame::gridFromWorld agree
/// bit for bit.
struct Projection {
    bool perspective = false;
    bool oriented = false; ///< orthographic with an arbitrary basis (right, up, forward)
    int axisX = 0, axisY = 1, axisS = 2;
    Vec3d origin;
    Vec3d scale{1, 1, 1};
    Vec3d eye, right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, 1};
    double tanX = 0, tanY = 0; ///< tangents of the half field of view across and up
    double halfW = 0, halfH = 0;
    /// Axis-aligned orthographic frames: the box's sides per world axis rounded to float (the
    /// precision of mesh vertices), and the grid's size along (axisX, axisY, axisS) = (W, H, D).
    Vec3f sideLo, sideHi;
    Vec3d size;

    VOXFX_HOSTDEV Vec3d cameraFromWorld(const Vec3d& p) const {
        const Vec3d q = p - eye;
        return {dot(q, right), dot(q, up), dot(q, forward)};
    }
    VOXFX_HOSTDEV double imageX(double cx, double cz) const { return (cx / (cz * tanX) + 1.0) * halfW; }
    VOXFX_HOSTDEV double imageY(double cy, double cz) const { return (cy / (cz * tanY) + 1.0) * halfH; }
    VOXFX_HOSTDEV VOXFX_ALWAYS_INLINE Vec3d gridFromWorld(const Vec3d& p) const {
        if (!perspective) {
            if (!oriented)
                return {(p[axisX] - origin[axisX]) * scale.x, (p[axisY] - origin[axisY]) * scale.y,
                        (p[axisS] - origin[axisS]) * scale.z};
            const Vec3d q = p - origin;
            return {dot(q, right) * scale.x, dot(q, up) * scale.y, dot(q, forward) * scale.z};
        }
        const Vec3d c = cameraFromWorld(p);
#if defined(__GNUC__) && !defined(__CUDACC__)
        // imageX and imageY with their two divisions in one two-lane instruction (the same
        // quotients: the shadow lookups project every shaded sample).
        using V2d = double __attribute__((vector_size(16)));
        const V2d q = V2d{c.x, c.y} / V2d{c.z * tanX, c.z * tanY};
        return {(q[0] + 1.0) * halfW, (q[1] + 1.0) * halfH, c.z};
#else
        return {imageX(c.x, c.z), imageY(c.y, c.z), c.z};
#endif
    }
    /// gridFromWorld for a mesh vertex of an axis-aligned orthographic frame: a coordinate that
    /// equals a side of the box at the vertices' precision (float(p) == float(side)) lands on that
    /// side exactly, 0 or W, H, D. Without it, the far side maps to (hi - lo) * (n / (hi - lo)),
    /// which rounds past n in about one case of twenty, and a box side that no float holds (a
    /// --bounds value such as -20.8600788) lies up to half a float step away from the vertex the
    /// mesh file meant to put on it: faces on the grid's sides then fell off the grid. The
    /// vertices move by less than a float step, each once for all its triangles, so closed meshes
    /// stay closed. Other frames: gridFromWorld.
    VOXFX_HOSTDEV Vec3d gridFromVertex(const Vec3d& p) const {
        Vec3d g = gridFromWorld(p);
        if (perspective || oriented) return g;
        const int axes[3] = {axisX, axisY, axisS};
        for (int k = 0; k < 3; ++k) {
            const float v = float(p[axes[k]]);
            if (v == sideLo[axes[k]])
                g[k] = 0;
            else if (v == sideHi[axes[k]])
                g[k] = size[k];
        }
        return g;
    }
};

/// A frame as kernels see it: trivially copyable, no std::vector. `local` points into the
/// Frame's local slicing table (columnCount entries) or is null for uniform slicing; the view is
/// valid while the Frame lives and its slicing is unchanged.
struct FrameView {
    Projection projection;
    int64_t width = 0, height = 0, depth = 0;
    DepthToSlice uniform;
    const DepthToSlice* local = nullptr;
    int64_t localCount = 0;

    VOXFX_HOSTDEV bool isPerspective() const { return projection.perspective; }
    VOXFX_HOSTDEV int64_t columnCount() const { return width * height; }
    /// The depth-to-slice map of column c = y * width + x.
    VOXFX_HOSTDEV DepthToSlice depthToSlice(int64_t column) const { return local ? local[column] : uniform; }
};
static_assert(std::is_trivially_copyable_v<FrameView>);

class Frame {
public:
    Frame() = default;

    /// Orthographic frame whose W x H x D cells tile `box` exactly, sliced along `axis`.
    /// W and H count cells along columnXAxis(axis) and columnYAxis(axis), D along the axis.
    /// Throws voxfx::Error for an empty or non-finite box or a zero dimension.
    static Frame orthographic(const Box3d& box, Axis axis, int64_t w, int64_t h, int64_t d);

    /// Oriented orthographic frame: W x H x D cells tile the world region whose local coordinates
    /// (p . right, p . up, p . forward) lie in `localBox`; columns along right (W) and up (H),
    /// slices along forward (D). The basis must be orthonormal and right-handed
    /// (cross(right, up) = forward) to 1e-9. Throws voxfx::Error otherwise, or for an empty or
    /// non-finite box or a zero dimension.
    static Frame orthographic(const Box3d& localBox, const Vec3d& right, const Vec3d& up,
                              const Vec3d& forward, int64_t w, int64_t h, int64_t d);

    /// Perspective frame for a camera or spot light at `eye` looking at `target`, with vertical
    /// field of view `fovY` (radians), W x H columns (pixels), and D slices spanning view
    /// distances [nearDepth, farDepth] along the view direction (world units, 0 < near < far).
    static Frame perspective(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double fovY, int64_t w,
                             int64_t h, double nearDepth, double farDepth, int64_t d);

    bool isPerspective() const { return perspective_; }
    /// Orthographic with an arbitrary basis (see the file comment).
    bool isOriented() const { return projection_.oriented; }
    Axis axis() const { return axis_; }
    int64_t width() const { return w_; }
    int64_t height() const { return h_; }
    int64_t depth() const { return d_; }
    int64_t columnCount() const { return w_ * h_; }

    /// Orthographic: the world box the grid tiles, and the world size of one cell per world axis.
    /// Oriented: the local box, and the cell size along (right, up, forward).
    const Box3d& box() const { return box_; }
    Vec3d cellSize() const { return cell_; }

    /// Grid coordinates of a world point (see the file comment). For perspective frames the
    /// point must lie in front of the eye (view depth > 0).
    VOXFX_ALWAYS_INLINE Vec3d gridFromWorld(const Vec3d& p) const { return projection_.gridFromWorld(p); }
    /// World point of grid coordinates (gx, gy, depth).
    VOXFX_ALWAYS_INLINE Vec3d worldFromGrid(const Vec3d& g) const;
    /// World-space centre of cell (x, y, s) under the frame's slicing.
    Vec3d cellCenter(int64_t x, int64_t y, int64_t s) const;

    /// Perspective: view depth of a world point (distance along the view direction).
    double viewDepth(const Vec3d& p) const { return dot(p - eye_, forward_); }
    const Vec3d& eye() const { return eye_; }
    /// Orthonormal camera basis (right, up, forward); orthographic: the column x, y and slice axes.
    const Vec3d& right() const { return right_; }
    const Vec3d& up() const { return up_; }
    const Vec3d& forward() const { return forward_; }
    double tanHalfFovY() const { return tanHalfY_; }

    /// Depth range covered by the uniform slicing (orthographic: [0, D]).
    double nearDepth() const { return near_; }
    double farDepth() const { return far_; }

    Slicing slicing() const { return local_.empty() ? Slicing::Uniform : Slicing::Local; }
    /// Switches to ED06's locally adapted slicing: column c covers depths [near[c], far[c]] with
    /// its D slices. Vectors of columnCount() entries; far[c] <= near[c] marks an empty column
    /// (it then keeps the uniform range). Throws voxfx::Error on a size mismatch.
    void setLocalSlicing(const std::vector<double>& nearPerColumn, const std::vector<double>& farPerColumn);
    void setUniformSlicing() { local_.clear(); }
    /// The depth-to-slice map of column c = y * width + x.
    DepthToSlice depthToSlice(int64_t column) const {
        return local_.empty() ? uniform_ : local_[static_cast<std::size_t>(column)];
    }
    /// The same grid moved by `offset` (world units): an axis-aligned orthographic frame whose box
    /// is box() + offset, with the same dimensions, axis and slicing (local slicing tables are
    /// in grid units, so they carry over). For meshes kept near the origin for precision and
    /// placed far from it (the Python module's float64 input). Cell sizes are recomputed from
    /// the moved box, so they may differ from cellSize() in the last bits. Throws voxfx::Error
    /// for perspective or oriented frames and non-finite offsets.
    Frame translated(const Vec3d& offset) const;
    /// True when both frames describe the same grid (same camera, dimensions and slicing).
    bool sameGrid(const Frame& o) const;

    /// The world -> grid projection (what gridFromWorld applies).
    const Projection& projection() const { return projection_; }
    /// The frame as kernels see it (see FrameView for how long it stays valid).
    FrameView view() const {
        return {projection_,           w_, h_, d_, uniform_, local_.empty() ? nullptr : local_.data(),
                int64_t(local_.size())};
    }

private:
    /// The fields every constructor sets from its (already checked) arguments: kind, slicing axis,
    /// dimensions, camera basis, uniform slicing over [nearDepth, farDepth] and the projection's
    /// camera (kind, eye, basis). The caller adds what is particular to its kind.
    static Frame withCamera(bool perspective, Axis axis, int64_t w, int64_t h, int64_t d, const Vec3d& eye,
                            const Vec3d& right, const Vec3d& up, const Vec3d& forward, double nearDepth,
                            double farDepth);
    /// Sets the box and the cell size cellSize() returns (kept, not recomputed: light lookups ask
    /// for it per shaded sample).
    void setBox(const Box3d& box);

    bool perspective_ = false;
    Axis axis_ = Axis::Z;
    int64_t w_ = 0, h_ = 0, d_ = 0;
    Box3d box_;
    // box_'s extent per cell (see cellSize()); a frame without a box (perspective) keeps the
    // default box's, -inf.
    Vec3d cell_{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                -std::numeric_limits<double>::infinity()};
    Vec3d eye_, right_{1, 0, 0}, up_{0, 1, 0}, forward_{0, 0, 1};
    double tanHalfY_ = 0, tanHalfX_ = 0;
    double near_ = 0, far_ = 0;
    DepthToSlice uniform_;
    std::vector<DepthToSlice> local_;
    Projection projection_;
};

// Inline: light lookups take a receiver plane from it per shaded sample.
inline Vec3d Frame::worldFromGrid(const Vec3d& g) const {
    if (projection_.oriented)
        return projection_.origin + right_ * (g.x * cell_.x) + up_ * (g.y * cell_.y) +
               forward_ * (g.z * cell_.z);
    if (!perspective_) {
        const int cx = columnXAxis(axis_), cy = columnYAxis(axis_), cs = sliceAxis(axis_);
        Vec3d p;
        p[cx] = box_.lo[cx] + g.x * cell_[cx];
        p[cy] = box_.lo[cy] + g.y * cell_[cy];
        p[cs] = box_.lo[cs] + g.z * cell_[cs];
        return p;
    }
    const double z = g.z;
    const double px = (g.x / (0.5 * double(w_)) - 1.0) * z * tanHalfX_;
    const double py = (g.y / (0.5 * double(h_)) - 1.0) * z * tanHalfY_;
    return eye_ + right_ * px + up_ * py + forward_ * z;
}

} // namespace voxfx
