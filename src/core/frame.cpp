#include "voxfx/frame.hpp"

#include <cmath>

namespace voxfx {

const char* toString(Axis a) { return enumName(a, kAxisNames); }
const char* toString(Slicing s) { return enumName(s, kSlicingNames); }

Frame Frame::withCamera(bool perspective, Axis axis, int64_t w, int64_t h, int64_t d, const Vec3d& eye,
                        const Vec3d& right, const Vec3d& up, const Vec3d& forward, double nearDepth,
                        double farDepth) {
    Frame f;
    f.perspective_ = perspective;
    f.axis_ = axis;
    f.w_ = w;
    f.h_ = h;
    f.d_ = d;
    f.eye_ = eye;
    f.right_ = right;
    f.up_ = up;
    f.forward_ = forward;
    f.near_ = nearDepth;
    f.far_ = farDepth;
    // Orthographic: [0, D] to D slices, scale exactly 1.
    f.uniform_ = {nearDepth, double(d) / (farDepth - nearDepth)};
    Projection& pr = f.projection_;
    pr.perspective = perspective;
    pr.eye = eye;
    pr.right = right;
    pr.up = up;
    pr.forward = forward;
    return f;
}

Frame Frame::orthographic(const Box3d& box, Axis axis, int64_t w, int64_t h, int64_t d) {
    if (box.empty() || !isFinite(box.lo) || !isFinite(box.hi))
        fail("orthographic frame needs a finite, non-empty box");
    if (w <= 0 || h <= 0 || d <= 0) fail("grid dimensions must be positive, got ", w, " x ", h, " x ", d);
    const int cx = columnXAxis(axis), cy = columnYAxis(axis), cs = sliceAxis(axis);
    const Vec3d ext = box.extent();
    if (!(ext[cx] > 0) || !(ext[cy] > 0) || !(ext[cs] > 0))
        fail("orthographic frame needs a box with positive extent along every axis");
    Vec3d r, u, fw;
    r[cx] = 1;
    u[cy] = 1;
    fw[cs] = 1;
    Frame f = withCamera(false, axis, w, h, d, box.lo, r, u, fw, 0, double(d));
    f.setBox(box);
    Projection& pr = f.projection_;
    pr.axisX = cx;
    pr.axisY = cy;
    pr.axisS = cs;
    pr.origin = box.lo;
    pr.scale = {double(w) / ext[cx], double(h) / ext[cy], double(d) / ext[cs]};
    pr.sideLo = Vec3f(box.lo);
    pr.sideHi = Vec3f(box.hi);
    pr.size = {double(w), double(h), double(d)};
    return f;
}

Frame Frame::orthographic(const Box3d& localBox, const Vec3d& right, const Vec3d& up, const Vec3d& forward,
                          int64_t w, int64_t h, int64_t d) {
    if (localBox.empty() || !isFinite(localBox.lo) || !isFinite(localBox.hi))
        fail("orthographic frame needs a finite, non-empty box");
    if (w <= 0 || h <= 0 || d <= 0) fail("grid dimensions must be positive, got ", w, " x ", h, " x ", d);
    if (!isFinite(right) || !isFinite(up) || !isFinite(forward))
        fail("oriented orthographic frame needs a finite basis");
    constexpr double tol = 1e-9;
    const bool unit = std::abs(length(right) - 1) <= tol && std::abs(length(up) - 1) <= tol &&
                      std::abs(length(forward) - 1) <= tol;
    const bool orthogonal = std::abs(dot(right, up)) <= tol && std::abs(dot(up, forward)) <= tol &&
                            std::abs(dot(forward, right)) <= tol;
    if (!unit || !orthogonal || !(length(cross(right, up) - forward) <= 1e-8))
        fail("oriented orthographic frame needs a right-handed orthonormal basis (right x up = forward)");
    const Vec3d ext = localBox.extent();
    if (!(ext.x > 0) || !(ext.y > 0) || !(ext.z > 0))
        fail("orthographic frame needs a box with positive extent along every axis");
    const Vec3d origin = right * localBox.lo.x + up * localBox.lo.y + forward * localBox.lo.z;
    Frame f = withCamera(false, Axis::Z, w, h, d, origin, right, up, forward, 0, double(d));
    Projection& pr = f.projection_;
    pr.oriented = true;
    pr.axisX = 0;
    pr.axisY = 1;
    pr.axisS = 2;
    pr.origin = origin;
    pr.scale = {double(w) / ext.x, double(h) / ext.y, double(d) / ext.z};
    f.setBox(localBox);
    return f;
}

Frame Frame::perspective(const Vec3d& eye, const Vec3d& target, const Vec3d& up, double fovY, int64_t w,
                         int64_t h, double nearDepth, double farDepth, int64_t d) {
    if (w <= 0 || h <= 0 || d <= 0) fail("grid dimensions must be positive, got ", w, " x ", h, " x ", d);
    if (!(fovY > 0 && fovY < M_PI)) fail("perspective field of view must lie in (0, pi) radians, got ", fovY);
    if (!(nearDepth > 0 && farDepth > nearDepth && std::isfinite(farDepth)))
        fail("perspective depth range needs 0 < near < far, got near ", nearDepth, ", far ", farDepth);
    const Vec3d fw = normalize(target - eye);
    const Vec3d r = normalize(cross(fw, up));
    if (length(fw) == 0 || length(r) == 0)
        fail("perspective frame: eye equals target or up is parallel to the view");
    Frame f = withCamera(true, Axis::Z, w, h, d, eye, r, cross(r, fw), fw, nearDepth, farDepth);
    f.tanHalfY_ = std::tan(fovY * 0.5);
    f.tanHalfX_ = f.tanHalfY_ * double(w) / double(h);
    Projection& pr = f.projection_;
    pr.tanX = f.tanHalfX_;
    pr.tanY = f.tanHalfY_;
    pr.halfW = 0.5 * double(w);
    pr.halfH = 0.5 * double(h);
    return f;
}

void Frame::setBox(const Box3d& box) {
    box_ = box;
    const Vec3d ext = box_.extent();
    if (projection_.oriented) {
        cell_ = {ext.x / double(w_), ext.y / double(h_), ext.z / double(d_)};
        return;
    }
    Vec3d n;
    n[columnXAxis(axis_)] = double(w_);
    n[columnYAxis(axis_)] = double(h_);
    n[sliceAxis(axis_)] = double(d_);
    cell_ = {ext.x / n.x, ext.y / n.y, ext.z / n.z};
}

Vec3d Frame::cellCenter(int64_t x, int64_t y, int64_t s) const {
    const DepthToSlice m = depthToSlice(y * w_ + x);
    const double depth = m.near + (double(s) + 0.5) / m.scale;
    return worldFromGrid({double(x) + 0.5, double(y) + 0.5, depth});
}

void Frame::setLocalSlicing(const std::vector<double>& nearPerColumn,
                            const std::vector<double>& farPerColumn) {
    const auto n = static_cast<std::size_t>(columnCount());
    if (nearPerColumn.size() != n || farPerColumn.size() != n)
        fail("local slicing needs one near and one far depth per column (", n, "), got ",
             nearPerColumn.size(), " and ", farPerColumn.size());
    local_.assign(n, uniform_);
    for (std::size_t c = 0; c < n; ++c) {
        const double lo = nearPerColumn[c], hi = farPerColumn[c];
        if (std::isfinite(lo) && std::isfinite(hi) && hi > lo) local_[c] = {lo, double(d_) / (hi - lo)};
    }
}

Frame Frame::translated(const Vec3d& offset) const {
    if (perspective_ || projection_.oriented) fail("only axis-aligned orthographic frames can be translated");
    if (!isFinite(offset)) fail("the translation of a frame must be finite");
    Box3d moved = box_;
    moved.lo = moved.lo + offset;
    moved.hi = moved.hi + offset;
    Frame f = orthographic(moved, axis_, w_, h_, d_);
    f.local_ = local_;
    return f;
}

bool Frame::sameGrid(const Frame& o) const {
    if (perspective_ != o.perspective_ || w_ != o.w_ || h_ != o.h_ || d_ != o.d_ || axis_ != o.axis_)
        return false;
    if (!perspective_ && !(box_ == o.box_)) return false;
    if (projection_.oriented != o.projection_.oriented) return false;
    if (projection_.oriented && !(right_ == o.right_ && up_ == o.up_ && forward_ == o.forward_)) return false;
    if (perspective_ && !(eye_ == o.eye_ && forward_ == o.forward_ && up_ == o.up_ &&
                          tanHalfY_ == o.tanHalfY_ && near_ == o.near_ && far_ == o.far_))
        return false;
    if (local_.size() != o.local_.size()) return false;
    for (std::size_t i = 0; i < local_.size(); ++i)
        if (local_[i].near != o.local_[i].near || local_[i].scale != o.local_[i].scale) return false;
    return true;
}

} // namespace voxfx
