// Tests of the Volume type (placement, trilinear sampling, frame) and the procedural smoke.
//
// Oracles: trilinear interpolation written here as the eight-corner weighted sum (not the nested
// lerps of the library); the property that trilinear interpolation reproduces affine functions;
// the Frame's own cell centres; smoke properties (determinism, range, shape).
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>

#include "test_util.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume.hpp"

namespace voxfx {
namespace {

Volume randomVolume(const Vec3i& dims, const Vec3d& lo, const Vec3d& spacing, uint32_t seed) {
    Volume v(dims, lo, spacing);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-10, 10);
    for (float& x : v.values()) x = u(rng);
    return v;
}

TEST(Volume, PlacementFollowsVoxelGridConvention) {
    const Volume v({4, 5, 6}, {-1, 2, 3}, {0.5, 0.25, 2});
    EXPECT_EQ(v.voxelCount(), 4 * 5 * 6);
    EXPECT_EQ(v.box().lo, Vec3d(-1, 2, 3));
    EXPECT_EQ(v.box().hi, Vec3d(-1 + 4 * 0.5, 2 + 5 * 0.25, 3 + 6 * 2.0));
    EXPECT_EQ(v.voxelCenter(1, 2, 3), Vec3d(-1 + 1.5 * 0.5, 2 + 2.5 * 0.25, 3 + 3.5 * 2.0));
    EXPECT_EQ(v.index(1, 2, 3), 1 + 4 * (2 + 5 * 3));
}

TEST(Volume, ConstructorRejectsBadDimensionsSpacingAndOrigin) {
    const double nan = std::nan("");
    EXPECT_THROW(Volume({0, 1, 1}, {0, 0, 0}, {1, 1, 1}), Error);
    EXPECT_THROW(Volume({1, -2, 1}, {0, 0, 0}, {1, 1, 1}), Error);
    EXPECT_THROW(Volume({int64_t(1) << 30, int64_t(1) << 30, 2}, {0, 0, 0}, {1, 1, 1}), Error);
    EXPECT_THROW(Volume({1, 1, 1}, {0, 0, 0}, {1, 0, 1}), Error);
    EXPECT_THROW(Volume({1, 1, 1}, {0, 0, 0}, {1, nan, 1}), Error);
    EXPECT_THROW(Volume({1, 1, 1}, {nan, 0, 0}, {1, 1, 1}), Error);
}

TEST(Volume, TrilinearSampleMatchesTheEightCornerFormula) {
    const Volume v = randomVolume({5, 4, 3}, {1, -2, 0.5}, {0.5, 1.5, 0.75}, 7);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u01(0, 1);
    for (int n = 0; n < 2000; ++n) {
        // A point within the lattice of voxel centres, where no clamping applies.
        const Vec3d c{0.5 + u01(rng) * 4, 0.5 + u01(rng) * 3, 0.5 + u01(rng) * 2}; // in voxel units
        const Vec3d p = v.lo() + c * v.spacing();
        const int64_t i = std::min<int64_t>(int64_t(c.x - 0.5), 3),
                      j = std::min<int64_t>(int64_t(c.y - 0.5), 2),
                      k = std::min<int64_t>(int64_t(c.z - 0.5), 1);
        const double fx = c.x - 0.5 - double(i), fy = c.y - 0.5 - double(j), fz = c.z - 0.5 - double(k);
        double expected = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
            const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
            expected += w * double(v.at(i + dx, j + dy, k + dz));
        }
        EXPECT_NEAR(v.sample(p), expected, 1e-4)
            << "at voxel coordinates " << c.x << ", " << c.y << ", " << c.z;
    }
}

// VolumeView::sampleVoxel at voxelCoordinates(p), which the volume pass calls once per sample and
// shares with the empty-space and light-grid lookups, against the trilinear formula as sample()
// computed it before (per axis: outside the box `outside`, clamped to the outermost centres within
// half a voxel of a face, else the centre below and the next; lerps in double along x, then y, then
// z): bit for bit, at random points inside and around the box, on its faces and voxel boundaries,
// for an upright and a turned volume with one axis of a single voxel; and sample(p) gives the same.
TEST(Volume, SampleFromVoxelCoordinatesIsTheClampedTrilinearBitForBit) {
    const Volume upright = randomVolume({5, 1, 4}, {1, -2, 0.5}, {0.5, 1.5, 0.75}, 17);
    Volume turned = upright;
    const double c = std::cos(0.4), s = std::sin(0.4);
    turned.setAxes({c, 0, -s}, {0, 1, 0}, {s, 0, c});
    const auto reference = [](const VolumeView& v, const Vec3d& p, float outside) {
        const int64_t n[3] = {v.nx, v.ny, v.nz};
        int64_t i0[3], i1[3];
        double t[3];
        for (int a = 0; a < 3; ++a) {
            const double u = v.voxelCoordinate(p, a);
            if (!(u >= 0 && u <= double(n[a]))) return outside;
            const double l = u - 0.5;
            if (l <= 0) {
                i0[a] = i1[a] = 0, t[a] = 0;
            } else if (l >= double(n[a] - 1)) {
                i0[a] = i1[a] = n[a] - 1, t[a] = 0;
            } else {
                i0[a] = int64_t(std::floor(l)), i1[a] = std::min(i0[a] + 1, n[a] - 1),
                t[a] = l - double(i0[a]);
            }
        }
        const auto at = [&](int dx, int dy, int dz) {
            return double(v.at(dx ? i1[0] : i0[0], dy ? i1[1] : i0[1], dz ? i1[2] : i0[2]));
        };
        const auto lerp = [](double a, double b, double f) { return a + (b - a) * f; };
        const double x00 = lerp(at(0, 0, 0), at(1, 0, 0), t[0]), x10 = lerp(at(0, 1, 0), at(1, 1, 0), t[0]);
        const double x01 = lerp(at(0, 0, 1), at(1, 0, 1), t[0]), x11 = lerp(at(0, 1, 1), at(1, 1, 1), t[0]);
        return float(lerp(lerp(x00, x10, t[1]), lerp(x01, x11, t[1]), t[2]));
    };
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u01(0, 1);
    for (const Volume* v : {&upright, static_cast<const Volume*>(&turned)}) {
        const VolumeView view = v->view();
        const Vec3i d = v->dims();
        int64_t inside = 0;
        for (int k = 0; k < 20000; ++k) {
            // Voxel coordinates up to a voxel beyond each face, some snapped to a voxel boundary.
            Vec3d w{u01(rng) * (d.x + 2) - 1, u01(rng) * (d.y + 2) - 1, u01(rng) * (d.z + 2) - 1};
            if (k % 3 == 0) w[k % 9 / 3] = std::round(w[k % 9 / 3] * 2) / 2;
            const Vec3d p = v->worldFromVoxel(w);
            const float want = reference(view, p, -7.0f);
            const float got = view.sampleVoxel(view.voxelCoordinates(p), -7.0f);
            ASSERT_EQ(std::bit_cast<uint32_t>(got), std::bit_cast<uint32_t>(want))
                << w.x << " " << w.y << " " << w.z;
            ASSERT_EQ(std::bit_cast<uint32_t>(v->sample(p, -7.0f)), std::bit_cast<uint32_t>(want));
            inside += want != -7.0f;
        }
        EXPECT_GT(inside, 2000); // a third of the points lie inside the box (its one-voxel axis)
        EXPECT_EQ(view.sampleVoxel(view.voxelCoordinates({std::nan(""), 0, 0}), 3.0f), 3.0f);
    }
}

TEST(Volume, TrilinearSampleReproducesAffineFunctions) {
    Volume v({6, 7, 8}, {-3, 1, 2}, {0.3, 0.2, 0.1});
    const auto f = [](const Vec3d& p) { return 1.5 + 2 * p.x - 3 * p.y + 0.5 * p.z; };
    for (int64_t k = 0; k < 8; ++k)
        for (int64_t j = 0; j < 7; ++j)
            for (int64_t i = 0; i < 6; ++i) v.at(i, j, k) = float(f(v.voxelCenter(i, j, k)));
    std::mt19937 rng(3);
    const Vec3d c0 = v.voxelCenter(0, 0, 0), c1 = v.voxelCenter(5, 6, 7);
    std::uniform_real_distribution<double> u(0, 1);
    for (int n = 0; n < 1000; ++n) {
        const Vec3d p{c0.x + u(rng) * (c1.x - c0.x), c0.y + u(rng) * (c1.y - c0.y),
                      c0.z + u(rng) * (c1.z - c0.z)};
        EXPECT_NEAR(v.sample(p), f(p), 1e-5);
    }
}

TEST(Volume, GradientOfAnAffineFieldIsExactWithAnisotropicSpacingAndTurnedAxes) {
    // f = 1.5 + a.p: central differences of the trilinear field are exact for it, also within
    // half a voxel of the faces (one-sided there) and whatever the spacing and the axes.
    const Vec3d a{2, -3, 0.5};
    const auto f = [&](const Vec3d& p) { return 1.5 + dot(a, p); };
    for (const bool turned : {false, true}) {
        Volume v({6, 7, 8}, {-3, 1, 2}, {0.3, 0.2, 0.1});
        if (turned) {
            const double c = std::cos(0.6), s = std::sin(0.6);
            v.setAxes({c, s, 0}, {-s * 0.8, c * 0.8, 0.6}, {s * 0.6, -c * 0.6, 0.8});
        }
        for (int64_t k = 0; k < 8; ++k)
            for (int64_t j = 0; j < 7; ++j)
                for (int64_t i = 0; i < 6; ++i) v.at(i, j, k) = float(f(v.voxelCenter(i, j, k)));
        std::mt19937 rng(7);
        std::uniform_real_distribution<double> u(0, 1);
        for (int n = 0; n < 1000; ++n) {
            const Vec3d p = v.worldFromVoxel({6 * u(rng), 7 * u(rng), 8 * u(rng)});
            const Vec3d g = v.gradient(p);
            EXPECT_NEAR(g.x, a.x, 1e-4) << turned;
            EXPECT_NEAR(g.y, a.y, 1e-4) << turned;
            EXPECT_NEAR(g.z, a.z, 1e-4) << turned;
        }
        // Outside the box, where sample() is constant: zero.
        EXPECT_EQ(v.gradient(v.worldFromVoxel({-0.01, 3, 3})), Vec3d(0, 0, 0));
        EXPECT_EQ(v.gradient(v.worldFromVoxel({3, 3, 8.01})), Vec3d(0, 0, 0));
    }
}

TEST(Volume, GradientIsTheCentralDifferenceOfNeighbouringVoxelsAndZeroWhereConstant) {
    const Volume v = randomVolume({5, 6, 7}, {1, -2, 0.5}, {0.5, 0.25, 2}, 11);
    const Vec3d h = v.spacing();
    for (int64_t k = 1; k + 1 < 7; ++k)
        for (int64_t j = 1; j + 1 < 6; ++j)
            for (int64_t i = 1; i + 1 < 5; ++i) {
                const Vec3d g = v.gradient(v.voxelCenter(i, j, k));
                EXPECT_NEAR(g.x, (double(v.at(i + 1, j, k)) - v.at(i - 1, j, k)) / (2 * h.x), 1e-5);
                EXPECT_NEAR(g.y, (double(v.at(i, j + 1, k)) - v.at(i, j - 1, k)) / (2 * h.y), 1e-5);
                EXPECT_NEAR(g.z, (double(v.at(i, j, k + 1)) - v.at(i, j, k - 1)) / (2 * h.z), 1e-5);
            }
    // At an outermost centre the difference is one-sided, to the centre itself.
    const Vec3d g = v.gradient(v.voxelCenter(0, 2, 3));
    EXPECT_NEAR(g.x, (double(v.at(1, 2, 3)) - v.at(0, 2, 3)) / h.x, 1e-5);
    // A constant volume has no gradient anywhere in its box, up to the faces (the field is clamped
    // there, not faded to the outside value).
    Volume c({4, 4, 4}, {0, 0, 0}, {1, 1, 1});
    std::fill(c.values().begin(), c.values().end(), 3.0f);
    for (const Vec3d& p : {Vec3d{0, 0, 0}, Vec3d{0.2, 2, 3.9}, Vec3d{4, 4, 4}, Vec3d{2, 2, 2}})
        EXPECT_EQ(c.gradient(p), Vec3d(0, 0, 0));
}

TEST(Volume, SampleAtCentresBorderAndOutside) {
    const Volume v = randomVolume({3, 3, 3}, {0, 0, 0}, {1, 1, 1}, 5);
    for (int64_t k = 0; k < 3; ++k)
        for (int64_t j = 0; j < 3; ++j)
            for (int64_t i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(v.sample(v.voxelCenter(i, j, k)), v.at(i, j, k));
    // Between a face and the outermost centres the nearest centre's value holds (clamped).
    EXPECT_FLOAT_EQ(v.sample({0.0, 0.5, 0.5}), v.at(0, 0, 0));
    EXPECT_FLOAT_EQ(v.sample({3.0, 2.75, 2.6}), v.at(2, 2, 2));
    // Outside the box, or at a NaN point: the outside value.
    EXPECT_EQ(v.sample({-0.01, 1, 1}), 0.0f);
    EXPECT_EQ(v.sample({1, 3.01, 1}, -7.0f), -7.0f);
    EXPECT_EQ(v.sample({1, 1, std::nan("")}, 2.0f), 2.0f);
    EXPECT_EQ(Volume().sample({0, 0, 0}, 4.0f), 4.0f);
}

TEST(Volume, MinAndMaxValues) {
    Volume v({2, 2, 2}, {0, 0, 0}, {1, 1, 1});
    v.at(1, 0, 1) = -3.5f;
    v.at(0, 1, 1) = 9.0f;
    EXPECT_EQ(v.minValue(), -3.5f);
    EXPECT_EQ(v.maxValue(), 9.0f);
}

TEST(Volume, FrameCellsAreTheVoxelsForEveryAxis) {
    const Volume v({3, 4, 5}, {1, -2, 0.5}, {0.5, 0.25, 2});
    for (const Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        SCOPED_TRACE(toString(axis));
        const Frame f = v.frame(axis);
        EXPECT_FALSE(f.isPerspective());
        EXPECT_EQ(f.box(), v.box());
        const int ax = columnXAxis(axis), ay = columnYAxis(axis), as = sliceAxis(axis);
        EXPECT_EQ(f.width(), v.dims()[ax]);
        EXPECT_EQ(f.height(), v.dims()[ay]);
        EXPECT_EQ(f.depth(), v.dims()[as]);
        for (int64_t s = 0; s < f.depth(); ++s)
            for (int64_t y = 0; y < f.height(); ++y)
                for (int64_t x = 0; x < f.width(); ++x) {
                    Vec3i ijk;
                    ijk[ax] = x;
                    ijk[ay] = y;
                    ijk[as] = s;
                    const Vec3d a = f.cellCenter(x, y, s), b = v.voxelCenter(ijk.x, ijk.y, ijk.z);
                    EXPECT_NEAR(a.x, b.x, 1e-12);
                    EXPECT_NEAR(a.y, b.y, 1e-12);
                    EXPECT_NEAR(a.z, b.z, 1e-12);
                }
    }
    EXPECT_THROW(Volume().frame(), Error);
}

TEST(Volume, ScalarTypeNamesRoundTrip) {
    for (const ScalarType t :
         {ScalarType::UInt8, ScalarType::Int8, ScalarType::UInt16, ScalarType::Int16, ScalarType::UInt32,
          ScalarType::Int32, ScalarType::Float32, ScalarType::Float64})
        EXPECT_EQ(scalarTypeFromString(toString(t)), t);
    EXPECT_EQ(scalarTypeFromString("double"), ScalarType::Float64);
    EXPECT_THROW(scalarTypeFromString("int64"), Error);
}

TEST(Smoke, IsDeterministicWhateverTheThreadCount) {
    SmokeParams p;
    p.dims = {24, 20, 32};
    p.seed = 42;
    Volume a, b;
    withThreads(1, [&] { a = makeSmoke(p); });
    withThreads(0, [&] { b = makeSmoke(p); });
    EXPECT_EQ(a.values(), b.values());
    EXPECT_EQ(makeSmoke(p).values(), a.values());
    p.seed = 43;
    EXPECT_NE(makeSmoke(p).values(), a.values());
}

TEST(Smoke, IsADensityInZeroOneShapedAsARisingPlume) {
    SmokeParams p;
    p.dims = {32, 32, 40};
    p.box = {{-2, -2, 0}, {2, 2, 5}};
    const Volume v = makeSmoke(p);
    EXPECT_EQ(v.dims(), p.dims);
    EXPECT_EQ(v.box().lo, p.box.lo);
    EXPECT_NEAR(v.box().hi.x, p.box.hi.x, 1e-12);
    EXPECT_NEAR(v.box().hi.z, p.box.hi.z, 1e-12);
    double sum = 0;
    for (const float x : v.values()) {
        EXPECT_TRUE(x >= 0 && x <= 1) << x;
        sum += x;
    }
    EXPECT_GT(v.maxValue(), 0.3f);
    EXPECT_GT(sum, 0.0);
    // Empty at the box's side edges (outside the cone) and in its top slices (faded out by 92 %).
    for (int64_t k = 0; k < 40; ++k) {
        EXPECT_EQ(v.at(0, 0, k), 0.0f);
        EXPECT_EQ(v.at(31, 16, k), 0.0f);
    }
    for (int64_t j = 0; j < 32; ++j)
        for (int64_t i = 0; i < 32; ++i) EXPECT_EQ(v.at(i, j, 39), 0.0f);
}

TEST(Smoke, RejectsBadParameters) {
    SmokeParams p;
    p.octaves = 0;
    EXPECT_THROW(makeSmoke(p), Error);
    p = {};
    p.dims = {0, 4, 4};
    EXPECT_THROW(makeSmoke(p), Error);
    p = {};
    p.box = Box3d{};
    EXPECT_THROW(makeSmoke(p), Error);
    p = {};
    p.frequency = std::nan("");
    EXPECT_THROW(makeSmoke(p), Error);
}

} // namespace
} // namespace voxfx
