/* LD_PRELOAD shim for bench/bench_python.py: makes Debian's Open3D 0.16 ray casting hit anything.
 *
 * Open3D's RaycastingScene fills every ray with mask = 0 (cpp/open3d/t/geometry/RaycastingScene.cpp),
 * which only works with an Embree built without ray masks, as Open3D's own bundled build is.
 * Debian's libembree3 3.13.5 is built with ray masks (rtcGetDeviceProperty(RAY_MASK_SUPPORTED) = 1)
 * and geometries keep the default mask 0xFFFFFFFF, so (ray.mask & geometry mask) == 0 and every
 * ray misses: cast_rays returns t_hit = inf, count_intersections 0, compute_occupancy all 0.
 *
 * This library defines the two ray entry points Open3D imports, sets every ray's mask to
 * 0xFFFFFFFF and calls Embree's own function. Nothing else changes.
 *
 *   cc -O2 -shared -fPIC -o open3d_embree_mask_fix.so bench/open3d_embree_mask_fix.c -ldl
 *   LD_PRELOAD=$PWD/open3d_embree_mask_fix.so python3 ...
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include <embree3/rtcore.h>

typedef void (*Intersect1M)(RTCScene, struct RTCIntersectContext*, struct RTCRayHit*, unsigned int, size_t);
typedef void (*Occluded1M)(RTCScene, struct RTCIntersectContext*, struct RTCRay*, unsigned int, size_t);

/* Embree's own symbol. Python loads Open3D (and Embree with it) with RTLD_LOCAL, so RTLD_NEXT does
 * not see it: ask for the already loaded library by name. */
static void* embree_symbol(const char* name) {
    void* lib = dlopen("libembree3.so.3", RTLD_NOW | RTLD_NOLOAD);
    void* f = lib ? dlsym(lib, name) : NULL;
    if (!f) {
        fprintf(stderr, "open3d_embree_mask_fix: %s not found in libembree3.so.3\n", name);
        abort();
    }
    return f;
}

void rtcIntersect1M(RTCScene scene, struct RTCIntersectContext* context, struct RTCRayHit* rays, unsigned int m,
                    size_t stride) {
    static Intersect1M real;
    Intersect1M f = __atomic_load_n(&real, __ATOMIC_ACQUIRE);
    if (!f) {
        f = (Intersect1M)embree_symbol("rtcIntersect1M");
        __atomic_store_n(&real, f, __ATOMIC_RELEASE);
    }
    for (unsigned int i = 0; i < m; ++i) ((struct RTCRayHit*)((char*)rays + i * stride))->ray.mask = 0xFFFFFFFFu;
    f(scene, context, rays, m, stride);
}

void rtcOccluded1M(RTCScene scene, struct RTCIntersectContext* context, struct RTCRay* rays, unsigned int m,
                   size_t stride) {
    static Occluded1M real;
    Occluded1M f = __atomic_load_n(&real, __ATOMIC_ACQUIRE);
    if (!f) {
        f = (Occluded1M)embree_symbol("rtcOccluded1M");
        __atomic_store_n(&real, f, __ATOMIC_RELEASE);
    }
    for (unsigned int i = 0; i < m; ++i) ((struct RTCRay*)((char*)rays + i * stride))->mask = 0xFFFFFFFFu;
    f(scene, context, rays, m, stride);
}
