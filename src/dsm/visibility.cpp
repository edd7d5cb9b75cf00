// voxfx — visibility functions of deep shadow maps: the streaming ε-compressor (Lokovic & Veach
// 2000, §4.1) and the per-texel builder. See voxfx/dsm.hpp for the conventions.
#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/dsm.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

DsmCompressor::DsmCompressor(double epsilon, std::vector<DsmNode>& out) { reset(epsilon, out); }

void DsmCompressor::reset(double epsilon, std::vector<DsmNode>& out) {
    out_ = &out;
    eps_ = std::max(0.0, epsilon);
    started_ = false;
    open_ = false;
    emitted_ = 0;
}

void DsmCompressor::emit(double z, double v) {
    out_->push_back({float(z), float(v)});
    ++emitted_;
}

void DsmCompressor::closeSegment() {
    // Any slope in [lo, hi] keeps the line inside every band since the origin; the midpoint leaves
    // room on both sides. The bands' lower edges are clamped at 0, so the line never goes negative
    // and no end value has to be raised (raising it would tilt the line out of earlier bands).
    // The clamps below only absorb rounding: into the band of the nodes at zl (so ε = 0 lands
    // exactly on the node), and below the origin (non-increasing).
    double v = vo_ + 0.5 * (lo_ + hi_) * (zl_ - zo_);
    v = std::min(std::max(v, std::max(vlMax_ - eps_, 0.0)), vlMin_ + eps_);
    v = std::min(std::max(v, 0.0), vo_);
    emit(zl_, v);
    zo_ = zl_;
    vo_ = v;
    open_ = false;
}

void DsmCompressor::push(double z, double v) {
    if (!started_) {
        emit(z, v);
        zo_ = z;
        vo_ = v;
        started_ = true;
        open_ = false;
        return;
    }
    VOXFX_DCHECK(z >= (open_ ? zl_ : zo_));
    if (!open_ && z <= zo_) {
        // Same depth as the origin: no slope constrains it, only the origin's value.
        if (std::abs(v - vo_) <= eps_) return;
        // A step. Of several nodes at one depth only the first and the last matter (the left and
        // right limits), so a second step at the same depth moves the existing "after" node.
        const size_t n = out_->size();
        if (emitted_ >= 2 && (*out_)[n - 2].z == float(zo_) && (*out_)[n - 1].z == float(zo_))
            (*out_)[n - 1].v = float(v);
        else
            emit(zo_, v);
        vo_ = v;
        return;
    }
    const double dz = z - zo_;
    // The band at this node, [v - ε, v + ε], with its lower edge clamped at 0 (visibility is never
    // negative; the clamped band is inside the ε-band, so the guarantee is unchanged).
    const double l = (std::max(v - eps_, 0.0) - vo_) / dz, h = (v + eps_ - vo_) / dz;
    const double nlo = open_ ? std::max(lo_, l) : l;
    const double nhi = std::min(open_ ? hi_ : 0.0, h); // slopes <= 0: non-increasing
    if (nlo <= nhi) {
        lo_ = nlo;
        hi_ = nhi;
        if (open_ && z == zl_) {
            vlMin_ = std::min(vlMin_, v);
            vlMax_ = std::max(vlMax_, v);
        } else {
            zl_ = z;
            vlMin_ = vlMax_ = v;
        }
        open_ = true;
        return;
    }
    // The band is empty: end the segment at the last accepted depth and restart from there. From
    // the new origin this node is either at the same depth (a step) or alone in a fresh interval,
    // which is never empty for a non-increasing input, so this recursion is one level deep.
    VOXFX_DCHECK(open_);
    closeSegment();
    push(z, v);
}

void DsmCompressor::finish() {
    if (open_) closeSegment();
    started_ = false;
    open_ = false;
    emitted_ = 0;
}

VisibilityBuilder::VisibilityBuilder(double epsilon, std::vector<DsmNode>& out)
    : comp_(epsilon, out), out_(&out), exact_(epsilon < 0) {}

void VisibilityBuilder::node(double z, double v) {
    // Events must come in depth order; tiny reorderings (rounding in the caller) are clamped.
    VOXFX_DCHECK(!any_ || z >= lastZ_ - 1e-6 * std::max(1.0, std::abs(lastZ_)));
    if (any_ && z < lastZ_) z = lastZ_;
    lastZ_ = z;
    any_ = true;
    if (exact_)
        out_->push_back({float(z), float(v)});
    else
        comp_.push(z, v);
}

void VisibilityBuilder::surface(double z, double alpha) {
    alpha = std::clamp(alpha, 0.0, 1.0);
    if (v_ <= 0 || alpha <= 0) return;
    node(z, v_);
    v_ = alpha >= 1 ? 0.0 : v_ * (1 - alpha);
    node(z, v_);
}

void VisibilityBuilder::volumeBegin(double z) {
    if (v_ <= 0) return;
    node(z, v_);
}

void VisibilityBuilder::volumeSample(double z, double sigma, double dz) {
    ramp(z, std::exp(-std::max(0.0, sigma * dz)));
}

void VisibilityBuilder::ramp(double z, double factor) {
    if (v_ <= 0) return;
    v_ *= std::clamp(factor, 0.0, 1.0);
    node(z, v_);
}

void VisibilityBuilder::finish() {
    if (!exact_) comp_.finish();
}

void buildVisibility(std::span<const DsmEvent> events, double epsilon, std::vector<DsmNode>& out) {
    // Elementary attenuations; at equal depth ramps arrive first, then steps, then segment starts.
    struct Element {
        double z;
        int kind;     // 0 ramp, 1 step, 2 segment start
        double value; // ramp: factor; step: alpha
        size_t order;
    };
    std::vector<Element> elements;
    size_t order = 0;
    for (size_t i = 0; i < events.size(); ++i) {
        const DsmEvent& e = events[i];
        if (!std::isfinite(e.z0) || !std::isfinite(e.z1))
            fail("deep shadow map event ", i, ": depth is not finite");
        if (e.kind == DsmEvent::Kind::Surface) {
            if (!(e.alpha >= 0 && e.alpha <= 1))
                fail("deep shadow map event ", i, ": opacity ", e.alpha, " is not in [0, 1]");
            elements.push_back({e.z0, 1, e.alpha, order++});
            continue;
        }
        if (!(e.z1 >= e.z0)) fail("deep shadow map event ", i, ": volume segment ends before it starts");
        if (!(e.sigma >= 0) || !std::isfinite(e.sigma))
            fail("deep shadow map event ", i, ": extinction ", e.sigma, " is not a finite value >= 0");
        if (e.samples < 1) fail("deep shadow map event ", i, ": a volume segment needs at least one sample");
        elements.push_back({e.z0, 2, 0.0, order++});
        const double dz = (double(e.z1) - double(e.z0)) / e.samples;
        const double factor = std::exp(-double(e.sigma) * dz);
        for (int32_t k = 1; k <= e.samples; ++k) {
            const double z = k == e.samples ? double(e.z1) : double(e.z0) + k * dz;
            elements.push_back({z, 0, factor, order++});
        }
    }
    std::sort(elements.begin(), elements.end(), [](const Element& a, const Element& b) {
        if (a.z != b.z) return a.z < b.z;
        if (a.kind != b.kind) return a.kind < b.kind;
        return a.order < b.order;
    });
    out.clear();
    VisibilityBuilder builder(epsilon, out);
    for (const Element& e : elements) {
        if (e.kind == 0)
            builder.ramp(e.z, e.value);
        else if (e.kind == 1)
            builder.surface(e.z, e.value);
        else
            builder.volumeBegin(e.z);
    }
    builder.finish();
}

} // namespace voxfx
