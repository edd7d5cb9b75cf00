// voxfx — shadow volumes' options (their named fields: the CLI's flags, a scene file's settings,
// the Python keywords) and statistics (sums over lights, the one-line summary).
#include <string>
#include <vector>

#include "voxfx/shadow_volume.hpp"
#include "voxfx/text.hpp"

namespace voxfx {

std::span<const OptionField<ShadowVolumeOptions>> ShadowVolumeOptions::fields() {
    using O = ShadowVolumeOptions;
    static const std::vector<OptionField<O>> table = [] {
        std::vector<OptionField<O>> t;
        OptionField<O> all =
            optionField<O>("volumeCulling",
                           "shadow volumes: ED06 culling and clamping (the same image; off: more fragments)",
                           OptionType::Flag);
        all.store = +[](O& o, const OptionValue& v) {
            o.cullReceivers = o.cullOccluded = o.clamp = o.clampRuns = o.cullShadowedParts =
                o.dropShadowedReceivers = std::get<bool>(v);
        };
        all.get = +[](const O& o) {
            return OptionValue(o.cullReceivers && o.cullOccluded && o.clamp && o.clampRuns &&
                               o.cullShadowedParts && o.dropShadowedReceivers);
        };
        t.push_back(all);
        t.push_back(flagOption<O, &O::cullReceivers>(
            "cullReceivers", "shadow volumes: skip volumes holding no visible receiver"));
        t.push_back(flagOption<O, &O::cullOccluded>(
            "cullOccluded", "shadow volumes: skip casters entirely in other casters' shadow"));
        t.push_back(flagOption<O, &O::cullShadowedParts>(
            "cullShadowedParts",
            "shadow volumes: drop the unlit triangles of a caster lying in other casters' shadow"));
        t.push_back(flagOption<O, &O::dropShadowedReceivers>(
            "dropShadowedReceivers", "shadow volumes: leave a receiver in another caster's shadow to that "
                                     "caster (culling, clamping)"));
        t.push_back(flagOption<O, &O::clamp>("volumeClamping",
                                             "shadow volumes: end each volume at its last receiver slab"));
        t.push_back(flagOption<O, &O::clampRuns>(
            "clampRuns",
            "shadow volumes: cut each volume to its runs of receiver slabs (near end and gaps)"));
        t.push_back(numberOption<O, &O::mapResolution>(
            "cullResolution", "shadow volumes: culling light views, columns along the longer side", 1,
            16384));
        t.push_back(numberOption<O, &O::receiverSlices>(
            "receiverSlices", "shadow volumes: slices of the receiver slicemap", 1, 16384));
        return t;
    }();
    return table;
}

ShadowVolumeStats& ShadowVolumeStats::operator+=(const ShadowVolumeStats& o) {
    casters += o.casters;
    culledNoReceiver += o.culledNoReceiver;
    culledOccluded += o.culledOccluded;
    clamped += o.clamped;
    nearClamped += o.nearClamped;
    gaps += o.gaps;
    culledTriangles += o.culledTriangles;
    droppedReceivers += o.droppedReceivers;
    depthPass += o.depthPass;
    depthFail += o.depthFail;
    silhouetteEdges += o.silhouetteEdges;
    volumeTriangles += o.volumeTriangles;
    fragments += o.fragments;
    receiversCovered = receiversCovered && o.receiversCovered;
    cullMs += o.cullMs;
    buildMs += o.buildMs;
    rasterMs += o.rasterMs;
    return *this;
}

std::string ShadowVolumeStats::summary() const {
    return countText(fragments) + " volume fragments; " + countText(culledNoReceiver + culledOccluded) +
           " of " + countText(casters) + " casters culled, " + countText(culledTriangles) +
           " shadowed triangles dropped, " + countText(clamped) + " clamped (" + countText(nearClamped) +
           " near ends, " + countText(gaps) + " gaps); " + countText(droppedReceivers) +
           " shadowed receiver cells left; culling " + msText(cullMs) + ", volumes " + msText(buildMs) +
           ", counting " + msText(rasterMs);
}

} // namespace voxfx
