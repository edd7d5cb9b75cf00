// The smallest program that renders: load a scene (a glTF or JSON scene, or any mesh loadMesh
// reads), take the options its file states, render it from its first camera (or the default one)
// with transmittance shadows, and write a PNG (render() tone-maps filmic, as for a display
// format). It includes render.hpp and the two file headers, not the techniques: BENCHMARKS.md
// ("#36 public headers") times what compiling it costs.
//
//   build/render_minimal data/meshes/bunny00.off bunny.png
#include <cstdio>

#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s SCENE OUT.png\n", argv[0]);
        return 2;
    }
    try {
        const voxfx::Scene scene = voxfx::loadScene(argv[1]);

        // The scene file's settings over the defaults; a technique by name, and its options by name
        // (the CLI's --grid-resolution, Python's grid_resolution).
        voxfx::RenderOptions options = voxfx::renderOptionsFor(scene, "transmittance");
        options.width = 640;
        options.height = 480;
        voxfx::setRenderOption(options, "gridResolution", voxfx::OptionValue(int64_t(128)));

        const voxfx::Camera camera =
            voxfx::sceneCamera(scene, 0, double(options.width) / double(options.height));
        const voxfx::RenderResult result = voxfx::render(scene, camera, options);
        voxfx::writePng(result.image, argv[2]);
        std::printf("%lld x %lld, %lld samples show geometry, %.1f ms\n", (long long)result.image.width,
                    (long long)result.image.height, (long long)result.coveredPixels, result.timings.totalMs);
    } catch (const voxfx::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
