// voxfx — the media a ray is in, for every method that follows light through glass: exact glass
// (src/render/exact_glass.cpp), voxel glass (voxel_glass.cpp) and exact shadows
// (exact_shadow.cpp). One stack: the innermost (last entered) medium on top, air when empty.
//
// What the three share: entering pushes a medium; leaving removes the innermost copy of a medium
// (nested objects of one material, or a face that leaves a medium the ray is not in: an open
// mesh's back face seen from outside, which each method answers in its own way); the indices of
// refraction on both sides of a crossing (n_from: current(), n_to: the stack after it, built as a
// copy); Beer–Lambert over a segment in the current medium (attenuation). Exact shadows attenuate
// by each medium over its whole chord instead: an entry remembers where along the ray it was
// entered (Entry::t).
//
// Thread-safety: a value; one per ray (exact shadows keep one per thread and reset it).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "voxfx/glass_optics.hpp"

namespace voxfx::detail {

class MediaStack {
public:
    /// A medium the ray is in: its index into the media, and where along the ray it was entered.
    struct Entry {
        uint32_t medium = 0;
        double t = 0;
    };

    MediaStack() = default;
    explicit MediaStack(std::span<const GlassMedium> media) : media_(media) {}

    /// Air, outside every medium (index of refraction 1, no attenuation, no tint).
    static const GlassMedium& air() {
        static const GlassMedium kAir{1.0f, {0, 0, 0}, {1, 1, 1}};
        return kAir;
    }

    /// Empties the stack and sets the media its indices refer to (keeps the storage: a stack reused
    /// per thread allocates once).
    void reset(std::span<const GlassMedium> media) {
        media_ = media;
        entries_.clear();
    }

    void enter(uint32_t medium, double t = 0) { entries_.push_back({medium, t}); }
    /// Leaves the innermost copy of `medium`: its entry, or nothing where the ray is not in it (the
    /// stack is unchanged then).
    std::optional<Entry> leave(uint32_t medium) {
        for (size_t i = entries_.size(); i-- > 0;)
            if (entries_[i].medium == medium) {
                const Entry e = entries_[i];
                entries_.erase(entries_.begin() + std::ptrdiff_t(i));
                return e;
            }
        return std::nullopt;
    }
    /// Leaves the innermost medium, whichever it is (the stack must not be empty).
    void leaveInnermost() { entries_.pop_back(); }
    /// Crosses from the innermost medium straight into `medium` (the face between two touching
    /// media; the stack must not be empty).
    void replaceInnermost(uint32_t medium) { entries_.back().medium = medium; }

    bool empty() const { return entries_.empty(); }
    /// The innermost medium's index (the stack must not be empty).
    uint32_t innermost() const { return entries_.back().medium; }
    std::span<const Entry> entries() const { return entries_; }
    /// The innermost medium, or air.
    const GlassMedium& current() const { return entries_.empty() ? air() : media_[entries_.back().medium]; }
    const GlassMedium& medium(uint32_t index) const { return media_[index]; }
    /// Beer–Lambert over `length` world units in the current medium.
    Vec3f attenuation(double length) const { return beerLambert(current().sigma, length); }

private:
    std::span<const GlassMedium> media_;
    std::vector<Entry> entries_;
};

} // namespace voxfx::detail
