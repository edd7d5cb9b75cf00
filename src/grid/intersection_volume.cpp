// voxfx — intersection volumes with an error bound (Eisemann & Décoret, "Single-Pass GPU Solid
// Voxelization for Real-Time Applications", GI 2008, §7: objects voxelized into one grid,
// combined bitwise, their intersection volume recovered by counting, for collision detection and
// haptic feedback). See voxfx/intersection_volume.hpp.
#include "voxfx/intersection_volume.hpp"

#include "voxfx/grid_query.hpp"

namespace voxfx {

namespace {

Mesh placed(const MeshView& mesh, const Mat4d& worldFromMesh) {
    Mesh m;
    m.positions.resize(mesh.vertexCount);
    for (std::size_t i = 0; i < mesh.vertexCount; ++i)
        m.positions[i] = Vec3f(worldFromMesh.point(mesh.vertex(i)));
    m.indices.assign(mesh.indices, mesh.indices + 3 * mesh.triangleCount);
    return m;
}

bool isIdentity(const Mat4d& t) {
    const Mat4d id;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (t.m[i][j] != id.m[i][j]) return false;
    return true;
}

} // namespace

VolumeEstimate estimateVolume(const VoxelGrid& centres, const CsgBounds& bounds) {
    VolumeEstimate e;
    e.cells = centres.bits.count();
    e.volume = filledVolume(centres);
    const BitGrid uncertain = csg(bounds.upper, bounds.lower, CsgOp::Difference);
    e.uncertainCells = uncertain.count();
    e.errorBound = filledVolume({centres.frame, uncertain});
    e.lowerVolume = filledVolume({centres.frame, bounds.lower});
    e.upperVolume = filledVolume({centres.frame, bounds.upper});
    return e;
}

VolumeEstimate intersectionVolume(const VoxelGrid& a, const VoxelGrid& b) {
    const VoxelGrid common = csg(a, b, CsgOp::Intersection); // checks the frames
    return estimateVolume(common, {common.bits, common.bits});
}

VolumeEstimate intersectionVolume(const VoxelGrid& grid, const MeshView& mesh, const Mat4d& worldFromMesh,
                                  const VoxelizeOptions& options) {
    validateMesh(mesh, "intersection volume");
    const Mesh moved = isIdentity(worldFromMesh) ? Mesh() : placed(mesh, worldFromMesh);
    const MeshView m = isIdentity(worldFromMesh) ? mesh : moved.view();
    // The grid's own cells are exact (lower = upper = its bits): the bounds are the mesh's,
    // cut to the grid.
    VoxelGrid centres{grid.frame, {}};
    CsgBounds b = voxelizeCsgBounds(m, grid.frame, options, &centres.bits);
    csgInPlace(centres.bits, grid.bits, CsgOp::Intersection);
    csgInPlace(b.lower, grid.bits, CsgOp::Intersection);
    csgInPlace(b.upper, grid.bits, CsgOp::Intersection);
    return estimateVolume(centres, b);
}

VolumeEstimate intersectionVolume(const MeshView& a, const Mat4d& worldFromA, const MeshView& b,
                                  const Mat4d& worldFromB, const FitOptions& fit,
                                  const VoxelizeOptions& options) {
    validateMesh(a, "intersection volume, first mesh");
    validateMesh(b, "intersection volume, second mesh");
    const Mesh ma = placed(a, worldFromA), mb = placed(b, worldFromB);
    FitOptions f = fit;
    if (f.bounds.empty()) {
        const Box3d ba = computeBounds(ma.view()), bb = computeBounds(mb.view());
        f.bounds = {max(ba.lo, bb.lo), min(ba.hi, bb.hi)};
        const Vec3d e = f.bounds.extent();
        // Boxes that do not overlap, or only touch: no volume in common.
        if (ba.empty() || bb.empty() || !(e.x > 0 && e.y > 0 && e.z > 0)) return {};
    }
    const Frame frame = fitFrame(f.bounds, f);
    VoxelGrid centres{frame, {}};
    BitGrid solidB;
    CsgBounds ca = voxelizeCsgBounds(ma.view(), frame, options, &centres.bits);
    const CsgBounds cb = voxelizeCsgBounds(mb.view(), frame, options, &solidB);
    csgInPlace(centres.bits, solidB, CsgOp::Intersection);
    csgInPlace(ca.lower, cb.lower, CsgOp::Intersection);
    csgInPlace(ca.upper, cb.upper, CsgOp::Intersection);
    return estimateVolume(centres, ca);
}

} // namespace voxfx
