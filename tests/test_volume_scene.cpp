// Tests of the Boolean volume scene (voxfx/volume_scene.hpp): its nodes against CGAL's inside tests
// (CGAL::Side_of_triangle_mesh) along the segments the fragment lists and the segment walker give,
// and its objects in scene files (volumes, transfer functions, Boolean shapes, placement, errors).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrLoadScaled;
using test::shapeInside;

TEST(VolumeSceneTest, BooleanNodesAgreeWithCgalInsideTestsAlongFragmentSegments) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VolumeScene s;
    const int32_t a = s.addLeaf(dsmrLoadScaled("elephant", {{-1, -1, -1}, {0.6, 0.6, 0.6}}));
    const int32_t b = s.addLeaf(dsmrLoadScaled("knot1", {{-0.5, -0.6, -0.7}, {1, 0.9, 0.8}}));
    const int32_t u = s.addNode(ShapeOp::Union, a, b), i = s.addNode(ShapeOp::Intersection, a, b),
                  d = s.addNode(ShapeOp::Difference, a, b), e = s.addNode(ShapeOp::Difference, b, u);
    for (int32_t n : {u, i, d, e}) {
        VolumeSceneObject o;
        o.shape = n;
        o.name = toString(s.nodes[std::size_t(n)].op);
        s.addObject(o);
    }
    s.validate();
    const FlatLeaves flat = flattenLeaves(s, false);
    const Frame frame = Frame::perspective({1.5, 1.1, 1.8}, {0, 0, 0}, {0, 1, 0}, 1.0, 64, 64, 0.5, 8, 1);
    const FragmentLists lists = FragmentLists::build(frame, flat.mesh.view());
    // Midpoints of every segment, with the walker's flags.
    std::vector<Vec3d> points;
    std::vector<std::vector<uint8_t>> flags;
    SegmentWalker walker(s, flat.triangleLeaf);
    for (int64_t y = 0; y < 64; ++y)
        for (int64_t x = 0; x < 64; ++x)
            walker.walk(
                lists.column(x, y), [](double, std::size_t, bool) { return true; },
                [&](double z0, double z1, std::span<const uint8_t> inside) {
                    if (z1 - z0 > 1e-5) {
                        points.push_back(
                            frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 0.5 * (z0 + z1)}));
                        flags.emplace_back(inside.begin(), inside.end());
                    }
                    return true;
                },
                true);
    ASSERT_GT(points.size(), 700u);
    const std::vector<int> inA = test::sideOfClosedMesh(s.leaves[0].view(), points);
    const std::vector<int> inB = test::sideOfClosedMesh(s.leaves[1].view(), points);
    ASSERT_EQ(inA.size(), points.size());
    ASSERT_EQ(inB.size(), points.size());
    int64_t wrong = 0, insideSome = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
        if (inA[k] == 0 || inB[k] == 0) continue;
        const std::vector<int> leaf{inA[k] > 0, inB[k] > 0};
        for (std::size_t o = 0; o < s.objects.size(); ++o) {
            const bool expected = shapeInside(s, s.objects[o].shape, leaf);
            wrong += expected != (flags[k][o] != 0);
            insideSome += expected;
        }
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(insideSome, 500);
}

TEST(DeepShadowSceneFileTest, VolumeObjectsTurnWithRotateAndKeepTheirSamples) {
    // The same smoke placed plainly and scaled, turned 90 degrees about z and moved: every sample
    // of the plain one is found at its turned place, and the default shape is the turned box.
    test::TempDir dir;
    auto load = [&](const std::string& placement) {
        test::writeFile(dir.file("s.json"), R"({"objects": [{"name": "smoke", "kind": "volume",
            "volume": {"smoke": {"dims": [6, 7, 8], "box": [[0, 0, 0], [1, 2, 1]]}},
            "transfer": {"opacity": [[0, 0], [1, 1]], "color": [[0, 1, 1, 1]]})" +
                                                placement + "}]}");
        return loadScene(dir.file("s.json"));
    };
    const Scene plain = load(R"(, "scale": 2)");
    const Scene turned = load(R"(, "scale": 2, "rotate": [0, 0, 1, 90], "translate": [5, 0, 0])");
    const Volume& a = *plain.volumeScene->volumes[0];
    const Volume& b = *turned.volumeScene->volumes[0];
    auto place = [](const Vec3d& p) { return Vec3d{5 - p.y, p.x, p.z}; };
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.2, 4.2);
    for (int i = 0; i < 2000; ++i) {
        const Vec3d p{u(rng) / 2, u(rng), u(rng) / 2};
        ASSERT_NEAR(b.sample(place(p), -1.0f), a.sample(p, -1.0f), 1e-5) << p.x << ", " << p.y << ", " << p.z;
    }
    const Mesh& box = turned.volumeScene->leaves[0];
    ASSERT_EQ(box.positions.size(), 8u);
    double volume6 = 0; // six times the signed volume: positive when the faces point out
    for (std::size_t t = 0; t < box.indices.size(); t += 3) {
        const Vec3d p0(box.positions[box.indices[t]]), p1(box.positions[box.indices[t + 1]]),
            p2(box.positions[box.indices[t + 2]]);
        volume6 += dot(p0, cross(p1, p2));
    }
    EXPECT_NEAR(volume6 / 6, 2.0 * 4.0 * 2.0, 1e-4);
    for (const Vec3f& q : box.positions) { // each corner is a turned corner of the plain box
        bool found = false;
        for (const Vec3f& r : plain.volumeScene->leaves[0].positions)
            found = found || length(Vec3d(q) - place(Vec3d(r))) < 1e-5;
        EXPECT_TRUE(found) << q.x << ", " << q.y << ", " << q.z;
    }
}

TEST(DeepShadowSceneFileTest, ObjectsWithVolumesTransferFunctionsAndBooleanShapesLoad) {
    test::TempDir dir;
    test::writeFile(dir.file("cube.off"),
                    "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
    test::writeFile(dir.file("tf.json"), R"({"opacity": [[0, 0], [1, 0.5]], "color": [[0, 1, 1, 1]]})");
    test::writeFile(dir.file("scene.json"), R"({
      "meshes": [{"file": "cube.off", "name": "floor", "scale": [4, 0.1, 4], "translate": [-2, -0.1, -2]}],
      "lights": [{"type": "spot", "position": [0, 5, 0], "direction": [0, -1, 0], "outerConeDegrees": 40}],
      "objects": [
        {"name": "smoke", "kind": "volume", "volume": {"smoke": {"dims": [8, 8, 8], "box": [[-1, 0, -1], [1, 2, 1]]}},
         "transfer": "tf.json", "opacityLength": 0.2,
         "shape": {"difference": [{"volumeBox": true}, {"mesh": "cube.off", "translate": [-0.5, 0.5, -0.5]}]}},
        {"name": "glass", "kind": "translucent", "opacity": 0.3, "shape": {"box": [[1, 0, 1], [1.5, 0.5, 1.5]]}},
        {"name": "lens", "kind": "opaque", "shape": {"intersection": [{"box": [[-2, 0, -2], [-1, 1, -1]]},
                                                                      {"mesh": "cube.off", "translate": [-1.5, 0.5, -1.5]}]}}
      ],
      "render": {"shadows": "deep"}
    })");
    const Scene s = loadScene(dir.file("scene.json"));
    ASSERT_TRUE(s.volumeScene);
    const VolumeScene& vs = *s.volumeScene;
    ASSERT_EQ(vs.objects.size(), 2u); // the plain translucent box became a scene mesh
    EXPECT_EQ(vs.objects[0].kind, ObjectKind::Volume);
    EXPECT_EQ(vs.nodes[std::size_t(vs.objects[0].shape)].op, ShapeOp::Difference);
    EXPECT_EQ(vs.nodes[std::size_t(vs.objects[1].shape)].op, ShapeOp::Intersection);
    EXPECT_EQ(vs.volumes[0]->dims(), (Vec3i{8, 8, 8}));
    EXPECT_DOUBLE_EQ(vs.objects[0].transfer.opacity(1.0), 0.5);
    ASSERT_EQ(s.meshes.size(), 2u);
    EXPECT_FLOAT_EQ(s.materials[s.meshes[1].material].opacity, 0.3f);
    EXPECT_TRUE(s.materials[s.meshes[1].material].blend); // the camera sees through it

    // Bad objects: a clear error naming the object, no scene.
    const std::pair<const char*, const char*> bad[] = {
        {R"({"name": "a", "kind": "fog", "shape": {"box": [[0,0,0],[1,1,1]]}})", "unknown kind"},
        {R"({"name": "b", "kind": "volume", "volume": {"smoke": {}}})", "needs \"transfer\""},
        {R"({"name": "c", "kind": "volume", "volume": {"smoke": {}}, "transfer": {"opacity": [[0, 2]], "color": [[0, 1, 1, 1]]}})",
         "opacity"},
        {R"({"name": "d", "kind": "volume", "volume": "missing.inr", "transfer": "tf.json"})", "missing.inr"},
        {R"({"name": "e", "kind": "opaque", "shape": {"difference": [{"box": [[0,0,0],[1,1,1]]}]}})",
         "two shapes"},
        {R"({"name": "f", "kind": "translucent", "opacity": 1.5, "shape": {"box": [[0,0,0],[1,1,1]]}})",
         "opacity"},
        {R"({"name": "g", "kind": "volume", "volume": {"smoke": {"frequency": -1}}, "transfer": "tf.json"})",
         "objects[0] 'g'.volume.smoke: smoke frequency"},
        {R"({"name": "h", "kind": "opaque", "shape": {"mesh": "gone.off"}})", "gone.off"}};
    for (const auto& [object, message] : bad) {
        test::writeFile(dir.file("bad.json"), std::string(R"({"objects": [)") + object + "]}");
        try {
            loadScene(dir.file("bad.json"));
            ADD_FAILURE() << "accepted " << object;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
            // Files it names and generators it calls fail with the scene file's name too.
            EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
        }
    }
}

} // namespace
} // namespace voxfx
