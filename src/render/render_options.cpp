// voxfx — the renderer's options by name (voxfx/render.hpp): RenderOptions' own fields, setting a
// name wherever the render uses it, a scene file's settings, and the catalog front ends list.
#include <set>

#include "render/technique_list.hpp"
#include "voxfx/render.hpp"

namespace voxfx {

std::span<const OptionField<RenderOptions>> RenderOptions::fields() {
    using O = RenderOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::width>("width", "image width, pixels", 1, 65536),
        numberOption<O, &O::height>("height", "image height, pixels", 1, 65536),
        numberOption<O, &O::supersample>("supersample", "render k x k samples per pixel everywhere", 1, 8),
        nameOption<O, parseAntiAliasing, optionName<AntiAliasing>, &O::antiAliasing>(
            "antiAliasing",
            "anti-aliasing: adaptive shades every sample of edge pixels and s of the s x s (N-rooks) in "
            "glass pixels whose light bends or steps between their neighbours', post blends the other "
            "pixels' luma edges (FXAA), full does both, off takes one sample per pixel",
            "off | post | adaptive | full", "aa"),
        numberOption<O, &O::adaptiveSamples>(
            "adaptiveSamples", "adaptive anti-aliasing: s x s samples in edge pixels (s in glass pixels)", 2,
            8),
        nameOption<O, parseToneMap, optionName<ToneMap>, &O::toneMap>(
            "toneMap",
            "output transform: filmic (ACES curve, highlights roll off), linear (scene-linear radiance "
            "times --exposure; PNG clips at 1; also 'clamp') or auto: linear for .exr/.pfm, filmic for "
            ".png",
            "auto | filmic | linear"),
        numberOption<O, &O::exposure>(
            "exposure",
            "multiplies the linear image; 0: automatic (key 0.18 over the frame's log-average luminance)", 0,
            1e6),
        numberOption<O, &O::skyLight>(
            "skyLight", "ambient light from the environment's irradiance, times this (0: none)", 0, 1e6),
        tripleOption<O, &O::ambient>("ambient", "constant ambient radiance added to the sky's, linear RGB", 0,
                                     1e6),
        nameOption<O, parseSkyKind, optionName<SkyKind>, &O::sky>(
            "sky",
            "the environment without --environment: procedural (Preetham's daylight sky with its sun, a "
            "ground of --ground-albedo below the horizon) or flat (--background everywhere); background, "
            "glass and ambient all use it",
            "procedural | flat"),
        tripleOption<O, &O::background>("background", "the flat sky's radiance, linear RGB", 0, 1e6),
        numberOption<O, &O::sunElevation>(
            "sunElevation", "procedural sky: the sun's degrees above the horizon (the default sun's too)", 1,
            90),
        numberOption<O, &O::sunAzimuth>("sunAzimuth",
                                        "procedural sky: the sun's degrees from -z (the default view) "
                                        "towards +x",
                                        -360, 360),
        numberOption<O, &O::turbidity>(
            "turbidity", "procedural sky: Preetham's turbidity, 2 (very clear) to 10 (hazy)", 1.7, 10),
        tripleOption<O, &O::groundAlbedo>(
            "groundAlbedo", "procedural sky: the albedo of the ground below the horizon, linear RGB", 0, 1),
        numberOption<O, &O::volumeStep>(
            "volumeStep", "volume ray casting: sample step in voxel spacings (each volume's smallest)", 1e-3,
            1000),
        flagOption<O, &O::skipEmptySpace>(
            "emptySpaceSkipping",
            "volumes: skip the bricks the transfer function leaves transparent (same image)"),
        numberOption<O, &O::volumeRefinement>(
            "volumeRefinement",
            "volume ray casting: cast every fourth pixel along x and y, then every second and then the "
            "rest only where a volume's, mesh's or depth edge or the silhouette of a volume's matter lies "
            "between them and the pixels 2 (then 1) apart, or those pixels' volume light departs from a "
            "straight line by more than this (shown luma, 0..1); interpolate elsewhere (0: cast every pixel)",
            0, 1),
        numberOption<O, &O::glassRefinement>(
            "glassRefinement",
            "glass: trace every other pixel along x and y, and the pixels between them only where their "
            "paths cross other glass or land on other objects or depths, or their light departs from a "
            "straight line by more than this (shown luma, 0..1); interpolate elsewhere (0: trace every "
            "pixel)",
            0, 1),
        numberOption<O, &O::glassSampleContrast>(
            "glassSampleContrast",
            "glass, adaptive anti-aliasing: a glass pixel gets its N-rooks samples where its shown light "
            "departs from the straight line through its neighbours' by more than this (shown luma, 0..1; "
            "smaller steps are left to the post-process)",
            0, 1),
        nameOption<O, parseVolumeShading, optionName<VolumeShading>, &O::volumeShading>(
            "volumeShading",
            "volumes: phong (DSM sec. 3.2) lights each sample by Blinn-Phong about its gradient normal "
            "(central differences of the volume): fully where the value changes by 5 % of its range per "
            "voxel, less where it changes less, not at all where the volume is homogeneous; none lights "
            "every sample alike from every direction",
            "none | phong"),
        flagOption<O, &O::defaultLights>("defaultLights",
                                         "light a scene without lights by a sun and the environment"),
        numberOption<O, &O::creaseAngle>(
            "creaseAngle",
            "meshes without normals: faces meeting at a wider angle (degrees) are not smoothed", 0, 180),
        nameOption<O, parseOcclusion, optionName<Occlusion>, &O::ambientOcclusion>(
            "ambientOcclusion",
            "ambient occlusion: darkens the sky's and the constant ambient light by how much of the "
            "hemisphere the opaque geometry hides within --occlusion-radius; screen finds it on the "
            "G-buffer (GTAO: fast, sees only what the camera sees), field cone-traces the geometry's "
            "distance field (slower, sees hidden and off-screen occluders); off lights every point by "
            "the whole sky",
            "off | screen | field", "ao"),
        numberOption<O, &O::occlusionRadius>(
            "occlusionRadius",
            "ambient occlusion: occluders farther than this (world units) do not darken; 0: a tenth of "
            "the median size of the opaque meshes that are not flat",
            0, 1e30),
        numberOption<O, &O::occlusionResolution>(
            "occlusionResolution", "ambient occlusion: distance field cells along its longest side", 8, 2048),
        numberOption<O, &O::translucencySlices>(
            "translucencySlices",
            "translucent solids (diffuse transmission): slices of the camera-space solid grid that "
            "measures the matter along each ray (GI08 sec. 7)",
            1, 65536),
        numberOption<O, &O::translucencyBlur>(
            "translucencyBlur",
            "translucent solids: what lies behind is blurred over a cone of this many radians per "
            "attenuationDistance of matter the ray crosses (at most 1 radian; 0: seen sharply, as "
            "through clear glass)",
            0, 100)};
    return table;
}

namespace {

// Sets `name` in the options `o` of one technique or method, when it has that field.
template <class Variant>
bool setInTechnique(Variant& chosen, const std::string& name, const OptionValue& v, std::string_view where,
                    std::string_view spelled) {
    bool used = false;
    std::visit(
        [&]<class O>(O& o) {
            if (const OptionField<O>* f = findOption(O::fields(), name)) {
                setOption(o, *f, v, where, spelled);
                used = true;
            }
        },
        chosen);
    return used;
}

const std::set<std::string>& knownNames() {
    static const std::set<std::string> names = [] {
        std::set<std::string> out;
        for (const RenderOptionInfo& i : renderOptionCatalog()) {
            out.insert(i.name);
            if (!i.alias.empty()) out.insert(i.alias);
        }
        return out;
    }();
    return names;
}

const OptionValue* sceneSetting(const Scene& scene, std::string_view name) {
    for (const auto& [key, value] : scene.settings.render)
        if (camelCase(key) == name) return &value;
    return nullptr;
}

// Appends the fields of O (used by `user`) to the catalog, merging names already listed.
template <class O> void catalogue(std::vector<RenderOptionInfo>& out, const std::string& user) {
    const O defaults{};
    for (const OptionField<O>& f : O::fields()) {
        RenderOptionInfo* info = nullptr;
        for (RenderOptionInfo& i : out)
            if (i.name == f.name) info = &i;
        if (!info) {
            info = &out.emplace_back();
            info->name = f.name;
            info->alias = f.alias;
            info->type = f.type;
            info->help = f.help;
            info->lo = f.lo;
            info->hi = f.hi;
            info->choices = f.choices;
        }
        VOXFX_CHECK(info->type == f.type); // one name, one type: a front end has one flag per name
        info->users.push_back(user + " (" + formatOption(f.get(defaults)) + ")");
    }
}

} // namespace

bool setRenderOption(RenderOptions& o, std::string_view nameIn, const OptionValue& v,
                     std::string_view where) {
    const std::string name = camelCase(nameIn);
    if (name == "shadows" || name == "glass") {
        const std::string* s = std::get_if<std::string>(&v);
        if (!s) detail::failOption(nameIn, where, "expected a name, got " + formatOption(v));
        try {
            if (name == "shadows")
                o.shadow = shadowOptionsNamed(*s);
            else
                o.glass = glassOptionsNamed(*s);
        } catch (const Error& e) { detail::failOption(nameIn, where, e.what()); }
        return true;
    }
    bool used = false;
    if (const OptionField<RenderOptions>* f = findOption(RenderOptions::fields(), name)) {
        setOption(o, *f, v, where, nameIn);
        used = true;
    }
    used = setInTechnique(o.shadow, name, v, where, nameIn) || used;
    used = setInTechnique(o.glass, name, v, where, nameIn) || used;
    if (!used && !knownNames().count(name)) {
        if (where.empty()) fail("unknown render option '", nameIn, "'");
        fail(where, ": unknown render option '", nameIn, "'");
    }
    return used;
}

void checkRenderSetting(std::string_view nameIn, const OptionValue& v, std::string_view where) {
    const std::string name = camelCase(nameIn);
    RenderOptions scratch;
    if (name == "shadows" || name == "glass") {
        setRenderOption(scratch, name, v, where);
        return;
    }
    // Every technique that has the name checks the value.
    bool known = setRenderOption(scratch, name, v, where);
    detail::forEachAlternative<ShadowOptions>([&]<class O>(std::type_identity<O>) {
        scratch.shadow = O{};
        known = setRenderOption(scratch, name, v, where) || known;
    });
    detail::forEachAlternative<GlassOptions>([&]<class O>(std::type_identity<O>) {
        scratch.glass = O{};
        known = setRenderOption(scratch, name, v, where) || known;
    });
    VOXFX_CHECK(known); // setRenderOption throws for names nobody knows
}

RenderOptions renderOptionsFor(const Scene& scene, std::string_view shadows, std::string_view glass) {
    RenderOptions o;
    const std::string where = (scene.source.empty() ? std::string("scene") : scene.source) + ": render";
    auto choose = [&](const char* what, std::string_view given) {
        if (!given.empty()) {
            setRenderOption(o, what, std::string(given));
            return true;
        }
        if (const OptionValue* v = sceneSetting(scene, what)) {
            setRenderOption(o, what, *v, where);
            return true;
        }
        return false;
    };
    choose("shadows", shadows);
    if (!choose("glass", glass)) o.glass = defaultGlass(scene);
    for (const auto& [key, value] : scene.settings.render) {
        const std::string name = camelCase(key);
        if (name != "shadows" && name != "glass") setRenderOption(o, name, value, where);
    }
    return o;
}

std::vector<RenderOptionInfo> renderOptionCatalog() {
    std::vector<RenderOptionInfo> out;
    catalogue<RenderOptions>(out, "render");
    detail::forEachAlternative<ShadowOptions>(
        [&]<class O>(std::type_identity<O>) { catalogue<O>(out, "shadows " + std::string(O::kName)); });
    detail::forEachAlternative<GlassOptions>(
        [&]<class O>(std::type_identity<O>) { catalogue<O>(out, "glass " + std::string(O::kName)); });
    return out;
}

double RenderTimings::ms(std::string_view name) const {
    double sum = 0;
    for (const PassTime& p : passes)
        if (p.name == name) sum += p.ms;
    return sum;
}

} // namespace voxfx
