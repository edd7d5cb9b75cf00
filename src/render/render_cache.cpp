// voxfx — RenderCache (voxfx/render.hpp) and the content keys of what it keeps
// (render/render_cache.hpp).
#include "render/render_cache.hpp"

#include <bit>

#include "render/glass_pass.hpp"

namespace voxfx {

RenderCache::RenderCache() : data_(std::make_unique<detail::RenderCacheData>()) {}
RenderCache::~RenderCache() = default;
RenderCache::RenderCache(RenderCache&&) noexcept = default;
RenderCache& RenderCache::operator=(RenderCache&&) noexcept = default;
void RenderCache::clear() { data_ = std::make_unique<detail::RenderCacheData>(); }

namespace detail {

namespace {

constexpr uint64_t kPrime1 = 0x9e3779b185ebca87ull, kPrime2 = 0xc2b2ae3d27d4eb4full;

uint64_t mixWord(uint64_t lane, uint64_t word) { return std::rotl(lane ^ (word * kPrime2), 31) * kPrime1; }

uint64_t finalMix(uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ull;
    return x ^ (x >> 33);
}

} // namespace

void Hasher::bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    uint64_t lane[4] = {h_, h_ + kPrime1, h_ + kPrime2, h_ - kPrime1};
    std::size_t i = 0;
    for (; i + 32 <= n; i += 32)
        for (int k = 0; k < 4; ++k) {
            uint64_t w;
            std::memcpy(&w, p + i + 8 * size_t(k), 8);
            lane[k] = mixWord(lane[k], w);
        }
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        std::memcpy(&w, p + i, 8);
        lane[0] = mixWord(lane[0], w);
    }
    uint64_t tail = 0;
    for (std::size_t k = 0; i + k < n; ++k) tail |= uint64_t(p[i + k]) << (8 * k);
    lane[1] = mixWord(lane[1], tail ^ (uint64_t(n) << 56));
    h_ = finalMix(lane[0] ^ std::rotl(lane[1], 7) ^ std::rotl(lane[2], 19) ^ std::rotl(lane[3], 37) ^ n);
}

void Hasher::option(const OptionValue& v) {
    value(v.index());
    std::visit(
        [&]<class T>(const T& x) {
            if constexpr (std::is_same_v<T, std::string>)
                string(x);
            else
                value(x);
        },
        v);
}

uint64_t meshesKey(const Scene& scene) {
    Hasher h;
    h.value(scene.meshes.size());
    for (const SceneMesh& m : scene.meshes) {
        h.array(m.mesh.positions);
        h.array(m.mesh.indices);
        h.array(m.normals);
        h.value(m.material);
    }
    // Volume objects are immutable behind their pointer (a const VolumeScene).
    h.value(reinterpret_cast<std::uintptr_t>(scene.volumeScene.get()));
    return h.get();
}

uint64_t materialsKey(const std::vector<Material>& materials) {
    Hasher h;
    h.value(materials.size());
    for (const Material& m : materials) {
        // Every field but the name. A field added to Material must be added here: the size check
        // below fails to compile until it is.
        static_assert(sizeof(Material) == sizeof(std::string) + 72, "hash the new Material field");
        h.value(m.baseColor), h.value(m.opacity), h.value(m.transmission), h.value(m.ior);
        h.value(m.thickness), h.value(m.attenuationColor), h.value(m.attenuationDistance);
        h.value(m.specular), h.value(m.shininess), h.value(m.doubleSided), h.value(m.blend);
        h.value(m.diffuseTransmission), h.value(m.diffuseTransmissionColor);
    }
    return h.get();
}

void hashLight(Hasher& h, const Light& l) {
    h.value(l.type), h.value(l.position), h.value(l.direction), h.value(l.color), h.value(l.intensity);
    h.value(l.innerConeAngle), h.value(l.outerConeAngle), h.value(l.range);
}

void hashCamera(Hasher& h, const Camera& c) {
    h.value(c.position), h.value(c.target), h.value(c.up), h.value(c.fovY), h.value(c.nearDepth);
    h.value(c.farDepth);
}

} // namespace detail
} // namespace voxfx
