// voxfx — loading environment maps (the image readers of voxfx/image_io.hpp, then the pyramid), and the
// one a scene renders under.
#include "voxfx/environment_io.hpp"

#include "voxfx/image_io.hpp"

namespace voxfx {

Environment loadEnvironment(const std::string& path) {
    if (path == "sky") return Environment::sky();
    return Environment(readImage(path));
}

std::shared_ptr<const Environment> loadSceneEnvironment(const Scene& scene, const RenderOptions& options,
                                                        const std::string& requested) {
    const std::string path = !requested.empty() ? requested : scene.settings.environmentMap;
    if (path.empty()) return nullptr; // render's own: the procedural sky, or the flat background
    if (path == "sky") return std::make_shared<const Environment>(Environment::sky(skyOptions(options)));
    return std::make_shared<const Environment>(loadEnvironment(path));
}

} // namespace voxfx
