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
/// RenderOptions::translucencySlices slices). Nothing when no sample shows one. What lies behind
/// is blurred (the solid scatters): averaged over 32 taps of a Vogel spiral over a disc of
/// focal * tan(cone) * (z_behind - z_surface) / z_behind samples (focal * tan(cone) for the
/// environment, which each tap reads blurred over the cone), cone = translucencyCone(material, L,
/// RenderOptions::translucencyBlur); taps landing on a surface in front of the solid's are left
/// out. A radius under half a sample reads the sample's own ray: blur 0 is the unblurred pass.
void compositeTranslucency(FrameState& frame);

/// The largest blur cone of a translucent solid (radians): its disc on what lies behind stays
/// within a few times the gap to it.
inline constexpr double kTranslucencyMaxCone = 1.0;

/// The half-angle (radians) of the cone over which a translucent solid of material `m` blurs what
/// lies behind it, `length` world units of it crossed: blur * length / m.attenuationDistance, at
/// most kTranslucencyMaxCone (0 for an infinite attenuationDistance, a zero length or blur 0).
double translucencyCone(const Material& m, double length, double blur);

} // namespace voxfx::detail
