// voxfx — what a RenderCache keeps between frames (internal; voxfx/render.hpp): each part with the
// key of what it was built from, and the frame buffers, reused so that a frame of the same size
// allocates (and page-faults) nothing large.
//
// Keys are 64-bit content hashes (Hasher): of the meshes (positions, indices, normals, material
// indices), the materials, the lights, the options a part reads (their named fields,
// voxfx/options.hpp) and, where a technique is fitted to the view, the camera. A part's key is
// cleared before it is rebuilt and set once the build succeeded, so a build that throws (a
// cancelled frame) leaves no stale part behind.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "render/screen_space_ao.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx::detail {

/// A 64-bit hash of bytes and values, for telling whether inputs changed (not cryptographic).
/// Four independent lanes over 8-byte words, so long arrays hash at several GB/s.
class Hasher {
public:
    void bytes(const void* data, std::size_t n);
    template <class T> void value(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes(&v, sizeof(T));
    }
    template <class T> void array(const std::vector<T>& v) {
        value(v.size());
        if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
    }
    void string(std::string_view s) {
        value(s.size());
        bytes(s.data(), s.size());
    }
    void option(const OptionValue& v);
    /// Every named field of options O (O::fields()), with the alternative's name.
    template <class O> void options(const O& o) {
        string(O::kName);
        for (const auto& f : O::fields())
            if (f.get) {
                string(f.name);
                option(f.get(o));
            }
    }
    template <class... O> void options(const std::variant<O...>& v) {
        value(v.index());
        std::visit([&](const auto& o) { options(o); }, v);
    }
    uint64_t get() const { return h_; }

private:
    uint64_t h_ = 0x243f6a8885a308d3ull;
};

/// The hash of a scene's meshes (what flattenScene and every technique read of them).
uint64_t meshesKey(const Scene& scene);
/// The hash of a scene's materials.
uint64_t materialsKey(const std::vector<Material>& materials);
void hashLight(Hasher& h, const Light& light);
void hashCamera(Hasher& h, const Camera& camera);

/// Whether technique options `o` fit what they build to the camera (frosted glass's view grid,
/// clustered deep shadows): `o.viewDependent()` where the options type has it.
template <class O> bool viewDependent(const O& o) {
    if constexpr (requires { o.viewDependent(); })
        return o.viewDependent();
    else
        return false;
}
template <class... O> bool viewDependent(const std::variant<O...>& v) {
    return std::visit([](const auto& o) { return viewDependent(o); }, v);
}

/// Built values by key, the most recently used first, at most `capacity` of them: switching back
/// and forth between techniques (a viewer's keys, a demo's shadow kinds) rebuilds nothing.
template <class T> class KeyedCache {
public:
    explicit KeyedCache(std::size_t capacity) : capacity_(capacity) {}
    /// The value built with `key`, moved to the front; null when there is none.
    std::shared_ptr<T> find(uint64_t key) {
        for (std::size_t i = 0; i < entries_.size(); ++i)
            if (entries_[i].first == key) {
                std::rotate(entries_.begin(), entries_.begin() + std::ptrdiff_t(i),
                            entries_.begin() + std::ptrdiff_t(i) + 1);
                return entries_.front().second;
            }
        return nullptr;
    }
    /// Keeps `value` under `key` at the front, dropping the least recently used beyond capacity.
    void insert(uint64_t key, std::shared_ptr<T> value) {
        entries_.insert(entries_.begin(), {key, std::move(value)});
        if (entries_.size() > capacity_) entries_.resize(capacity_);
    }
    void setCapacity(std::size_t capacity) {
        capacity_ = capacity;
        if (entries_.size() > capacity_) entries_.resize(capacity_);
    }

private:
    std::size_t capacity_;
    std::vector<std::pair<uint64_t, std::shared_ptr<T>>> entries_;
};

/// Per triangle of the flattened scene, what reconstructing a surface point of it needs
/// (render/shading.hpp, surfaceFromBasis): its first corner, barycentric duals (the weights of b
/// and c at a point p of its plane are dot(p - a, toB) and dot(p - a, toC)), and its unit face
/// normal (zero when degenerate); and the vertex normals of its three corners (SceneGeometry::normals
/// of its indices), copied here so that interpolatedNormal reads one record per sample instead of
/// the index buffer and then three vertices scattered over the scene.
struct TriangleBasis {
    Vec3f a, toB, toC, normal;
    Vec3f cornerNormal[3];
};

/// The glass pass's structures (render/glass_pass.cpp): built once per glass key.
struct GlassSetup;
/// The volume pass's structures (render/volume_pass.cpp): built once per volume key.
struct VolumeSetup;
/// The volume pass's deep-shadow visibility per volume of one light (render/volume_light_grid.hpp):
/// built once per volume key and light's shadow key.
struct VolumeLightGrids;

struct RenderCacheData {
    std::optional<uint64_t> geometryKey;
    SceneGeometry geometry;
    std::vector<TriangleBasis> triangleBases; ///< of `geometry`
    std::vector<TriangleTag> triangleTags;    ///< of `geometry` and the materials' opacity
    /// Built shadows of every light and technique used lately (several kinds per light).
    KeyedCache<LightShadow> shadows{8};
    KeyedCache<const FieldOcclusionSetup> occlusionSetup{2};
    KeyedCache<const AmbientOcclusion> occlusion{2};
    KeyedCache<const GlassSetup> glass{3};
    KeyedCache<const VolumeSetup> volume{2};
    KeyedCache<const VolumeLightGrids> volumeLight{4};
    // Frame buffers: overwritten every frame, kept for their memory.
    GBuffer gbuffer;
    std::vector<Vec3f> shaded;
    std::vector<float> screenOcclusion;
    std::vector<uint8_t> refined, glassSamples;
    std::vector<Vec3f> volumeBehind; ///< the volume pass: per cell, the light behind its volumes
    /// The volume pass: per cell, the light its representative's ray gathered (or the lattice's
    /// interpolation gave), its transmittance and the depth where its opacity reached one half (+inf:
    /// never), from which the cells of the next lattice level are interpolated.
    std::vector<Vec3f> volumeColor;
    std::vector<double> volumeTransmittance;
    std::vector<float> volumeFirstHit;
    std::vector<float> volumeLuma; ///< the volume pass: per cell, its representative's shown luma (AA round)
    FragmentLists volumeLists;     ///< the volume pass: its fragment lists, rebuilt every frame
    struct ScreenOcclusion {       ///< the screen-space occlusion's opaque materials, and its scratch
        std::vector<uint8_t> opaque;
        ScreenSpaceOcclusionScratch scratch;
    } screen;
    struct Resolve {
        std::vector<uint8_t> refined, skip, rows;
        std::vector<float> luma; ///< the post-process's, of the box-filtered image
        std::vector<std::vector<std::pair<std::size_t, Vec3f>>> blends; ///< the post-process's, per band
    } resolve;
};

} // namespace voxfx::detail
