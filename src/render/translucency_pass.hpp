// voxfx — the translucency pass (internal): the camera's view through translucent solids (GI08 §7;
// Material::isTranslucent, see render.hpp).
#pragma once

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// Adds to every shaded sample showing a translucent solid the light from behind it: what the
/// G-buffer without the translucent meshes shows there (shaded, or the environment along the ray)
/// times diffuseTransmission times beerLambert(attenuationCoefficient(material), L), L the world
/// length of translucent matter between the surface and what lies behind, counted along the
/// centre ray of the sample's output pixel (ViewMatter at the output resolution,
/// RenderOptions::translucencySlices slices). Nothing when no sample shows one.
void compositeTranslucency(FrameState& frame);

} // namespace voxfx::detail
