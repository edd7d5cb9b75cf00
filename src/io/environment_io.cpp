// voxfx — loading environment maps (the image readers of io/image.cpp, then the pyramid).
#include "voxfx/environment.hpp"
#include "voxfx/image_io.hpp"

namespace voxfx {

Environment loadEnvironment(const std::string& path) {
    if (path == "sky") return Environment::sky();
    return Environment(readImage(path));
}

} // namespace voxfx
