// voxfx — marching cubes on scalar fields (voxfx/volume_to_mesh.hpp): OpenVDB's volumeToMesh behind
// the voxfx_vdb module, its quads split into triangles turned to face outwards, and area-weighted
// vertex normals. In io/ because the module is io's (module_api.hpp).
#include "voxfx/volume_to_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace volume_mesh_detail {

void checkAdaptivity(const VolumeToMeshOptions& o) {
    if (!(o.adaptivity >= 0 && o.adaptivity <= 1))
        fail("marching cubes: adaptivity must lie in [0, 1], got ", o.adaptivity);
    if (!std::isfinite(o.isovalue)) fail("marching cubes: the iso value is not finite");
}

// OpenVDB's polygons as a SurfaceMesh: quads split along their 0-2 diagonal, every corner order
// reversed: OpenVDB winds a level set's polygons clockwise seen from outside (the side above the
// iso value; the outward-normal tests check the result); normals the area-weighted means.
SurfaceMesh toSurfaceMesh(const detail::VdbPolygons& p) {
    SurfaceMesh m;
    const std::size_t n = p.points.size() / 3;
    m.positions.resize(n);
    for (std::size_t i = 0; i < n; ++i)
        m.positions[i] = {p.points[3 * i], p.points[3 * i + 1], p.points[3 * i + 2]};
    m.indices.reserve(p.triangles.size() + p.quads.size() / 4 * 6);
    const auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
        m.indices.insert(m.indices.end(), {a, c, b});
    };
    for (std::size_t t = 0; t + 2 < p.triangles.size(); t += 3)
        add(p.triangles[t], p.triangles[t + 1], p.triangles[t + 2]);
    for (std::size_t q = 0; q + 3 < p.quads.size(); q += 4) {
        add(p.quads[q], p.quads[q + 1], p.quads[q + 2]);
        add(p.quads[q], p.quads[q + 2], p.quads[q + 3]);
    }
    // Area-weighted vertex normals: the cross products summed in triangle order (deterministic).
    std::vector<Vec3d> sum(n);
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3d a(m.positions[m.indices[t]]), b(m.positions[m.indices[t + 1]]),
            c(m.positions[m.indices[t + 2]]);
        const Vec3d normal = cross(b - a, c - a);
        for (int k = 0; k < 3; ++k) sum[m.indices[t + std::size_t(k)]] += normal;
    }
    m.normals.resize(n);
    for (std::size_t i = 0; i < n; ++i) m.normals[i] = Vec3f(normalize(sum[i]));
    return m;
}

void volumeMeshParallelFor(int64_t begin, int64_t end, int64_t grain, void* body,
                           void (*call)(void* body, int64_t b, int64_t e)) {
    parallelFor(begin, end, grain, [&](int64_t b, int64_t e) { call(body, b, e); });
}

void checkBand(double isovalue, double background, const char* what) {
    if (!(std::abs(isovalue) < background))
        fail("marching cubes: the iso value ", isovalue, " lies outside the ", what, "'s band (|iso| < ",
             background, "): the field holds only +-", background, " there");
}

} // namespace volume_mesh_detail

namespace vmd = volume_mesh_detail;

SurfaceMesh volumeToMesh(const ScalarFieldView& field, const VolumeToMeshOptions& options) {
    vmd::checkAdaptivity(options);
    const Vec3i d = field.dims;
    const int64_t kMaxIndex = std::numeric_limits<int32_t>::max() - 8;
    for (int a = 0; a < 3; ++a) {
        if (d[a] < 1 || d[a] > kMaxIndex)
            fail("marching cubes: the field's dimensions must lie in 1..", kMaxIndex, ", got ", d.x, " x ",
                 d.y, " x ", d.z);
        if (!(field.spacing[a] > 0) || !std::isfinite(field.spacing[a]))
            fail("marching cubes: the spacing must be finite and positive, got ", field.spacing[a]);
        if (!std::isfinite(field.origin[a])) fail("marching cubes: the origin is not finite");
    }
    const auto count = std::size_t(d.x) * std::size_t(d.y) * std::size_t(d.z);
    if (!field.values) fail("marching cubes: no values");
    // The module's inside is below the iso value: insideAbove negates the field and the iso value.
    const double sign = options.insideAbove ? -1 : 1;
    std::vector<float> negated;
    const float* values = field.values;
    if (options.insideAbove) {
        negated.resize(count);
        parallelFor(0, int64_t(count), 1 << 16, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) negated[std::size_t(i)] = -field.values[i];
        });
        values = negated.data();
    }
    // The largest value and the check for NaN and infinities, in one reduction.
    struct Extent {
        float hi = -std::numeric_limits<float>::infinity();
        int64_t bad = -1;
    };
    const Extent extent = parallelReduce(
        int64_t(0), int64_t(count), int64_t(1) << 16, Extent{},
        [&](int64_t b, int64_t e) {
            Extent x;
            for (int64_t i = b; i < e; ++i) {
                const float v = values[i];
                if (!std::isfinite(v)) {
                    if (x.bad < 0) x.bad = i;
                } else {
                    x.hi = std::max(x.hi, v);
                }
            }
            return x;
        },
        [](Extent a, const Extent& b) {
            a.hi = std::max(a.hi, b.hi);
            if (a.bad < 0) a.bad = b.bad;
            return a;
        });
    if (extent.bad >= 0) {
        const int64_t n = extent.bad;
        const int64_t i = field.zFastest ? n / (d.y * d.z) : n % d.x,
                      j = field.zFastest ? n / d.z % d.y : n / d.x % d.y,
                      k = field.zFastest ? n % d.z : n / (d.x * d.y);
        fail("marching cubes: the value at (", i, ", ", j, ", ", k, ") is ", field.values[extent.bad],
             " (values must be finite)");
    }
    const double iso = sign * options.isovalue;
    // Outside the array: a value above every sample and the iso value, so the box closes surfaces.
    const double top = std::max(double(extent.hi), iso);
    const auto background = float(top + std::max(1.0, std::abs(top)));
    detail::VdbPlacement placement;
    for (int a = 0; a < 3; ++a) {
        placement.cell[a] = field.spacing[a];
        placement.centre0[a] = field.origin[a];
    }
    const int64_t dims[3] = {d.x, d.y, d.z};
    detail::VdbPolygons polygons;
    std::string error;
    if (!detail::vdbModule().denseToMesh(values, dims, field.zFastest, placement, background, iso,
                                         options.adaptivity, vmd::volumeMeshParallelFor, &polygons, &error))
        fail("marching cubes: ", error);
    return vmd::toSurfaceMesh(polygons);
}

SurfaceMesh volumeToMesh(const LevelSet& levelSet, const VolumeToMeshOptions& options) {
    vmd::checkAdaptivity(options);
    if (!levelSet.valid()) fail("marching cubes: the level set is empty (no grid)");
    if (options.insideAbove)
        fail("marching cubes: a level set is negative inside; insideAbove does not apply");
    vmd::checkBand(options.isovalue, levelSet.background(), "level set");
    detail::VdbPolygons polygons;
    std::string error;
    if (!detail::vdbModule().levelSetToMesh(levelSet.handle(), options.isovalue, options.adaptivity,
                                            &polygons, &error))
        fail("marching cubes: ", error);
    return vmd::toSurfaceMesh(polygons);
}

SurfaceMesh volumeToMesh(const SignedDistanceField& field, const VolumeToMeshOptions& options) {
    vmd::checkAdaptivity(options);
    if (options.insideAbove)
        fail("marching cubes: a signed distance field is negative inside; insideAbove does not apply");
    if (!field.full) {
        vmd::checkBand(options.isovalue, field.background, "signed distance field");
        return volumeToMesh(LevelSet::fromField(field), options);
    }
    const std::vector<float> values = field.dense();
    ScalarFieldView view;
    view.values = values.data();
    view.dims = field.dims();
    view.spacing = field.frame.cellSize();
    view.origin = field.frame.box().lo + view.spacing * 0.5;
    return volumeToMesh(view, options);
}

} // namespace voxfx
