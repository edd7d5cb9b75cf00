// voxfx_embree — the Embree 3 module: nearest-hit queries on one triangle mesh (see
// render/embree_api.hpp and render/glass_tracer.cpp).
#include <cmath>
#include <cstring>
#include <limits>

#include <embree3/rtcore.h>

#include "render/embree_api.hpp"

namespace voxfx::detail {

namespace {

struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
};

void releaseScene(void* p) {
    auto* s = static_cast<EmbreeScene*>(p);
    if (!s) return;
    if (s->scene) rtcReleaseScene(s->scene);
    if (s->device) rtcReleaseDevice(s->device);
    delete s;
}

void* createScene(const float* positions, std::size_t vertexCount, const uint32_t* indices,
                  std::size_t triangleCount, std::string* error) {
    auto* s = new EmbreeScene;
    s->device = rtcNewDevice(nullptr);
    if (!s->device) {
        *error = "Embree could not create a device";
        releaseScene(s);
        return nullptr;
    }
    s->scene = rtcNewScene(s->device);
    // Watertight: a ray through an edge between two triangles hits one of them. Without it, a ray
    // along a sphere's ring of edges missed the face lying on the one it hit (a core touching its
    // shell: NestedGlassTest.BothTracersCrossACoreTouching...), and could pass between two faces.
    rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geom = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), vertexCount));
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), triangleCount));
    if (!v || !t) {
        *error = "Embree could not allocate the mesh buffers";
        rtcReleaseGeometry(geom);
        releaseScene(s);
        return nullptr;
    }
    std::memcpy(v, positions, vertexCount * 3 * sizeof(float));
    std::memcpy(t, indices, triangleCount * 3 * sizeof(uint32_t));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(s->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(s->scene);
    if (rtcGetDeviceError(s->device) != RTC_ERROR_NONE) {
        *error = "Embree failed to build the scene";
        releaseScene(s);
        return nullptr;
    }
    return s;
}

bool intersect(const void* p, const float origin[3], const float dir[3], float tNear, float tFar, float* t,
               uint32_t* triangle, float* u, float* v) {
    const auto* s = static_cast<const EmbreeScene*>(p);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = origin[0];
    rh.ray.org_y = origin[1];
    rh.ray.org_z = origin[2];
    rh.ray.dir_x = dir[0];
    rh.ray.dir_y = dir[1];
    rh.ray.dir_z = dir[2];
    rh.ray.tnear = tNear;
    rh.ray.tfar = tFar;
    rh.ray.time = 0;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(s->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    *t = rh.ray.tfar;
    *triangle = rh.hit.primID;
    *u = rh.hit.u;
    *v = rh.hit.v;
    return true;
}

constexpr EmbreeModule kTable{kEmbreeModuleAbi, sizeof(EmbreeModule), createScene, releaseScene, intersect};

} // namespace
} // namespace voxfx::detail

extern "C" const void* voxfx_module_embree(uint32_t abi) {
    return abi == voxfx::detail::kEmbreeModuleAbi ? &voxfx::detail::kTable : nullptr;
}
