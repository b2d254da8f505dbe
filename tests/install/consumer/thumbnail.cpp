// Renders a scene twice from one load, as a program embedding Cuberille would, and checks what
// came back: the frame's size, that something was drawn over the background, that the second
// render of the same settings gives the same bytes, and that bad input is an exception.
// Usage: thumbnail [SCENE]  (default: the built-in scene "demo"). Exit 0 when all hold.

#include <cstdio>
#include <string>

#include "render/library_version.h"
#include "render/renderer.h"
#include "scene/input_error.h"

int main(int argc, char** argv) {
    using namespace cuberille;
    const std::string name = argc > 1 ? argv[1] : "demo";
    const render::LoadedScene scene(name);
    render::FrameSettings frame;
    frame.width = 96;
    frame.height = 54;
    frame.msaa = 4;
    const render::RenderResult first = render::render(scene, frame);
    const std::vector<uint8_t> pixels = render::displayPixels(scene, frame, first);
    const std::vector<uint8_t> again = render::displayPixels(scene, frame, render::render(scene, frame));
    size_t differentFromCorner = 0;
    for (size_t i = 0; i < pixels.size(); i += 4)
        differentFromCorner += pixels[i] != pixels[0] || pixels[i + 1] != pixels[1] || pixels[i + 2] != pixels[2];
    bool refused = false;
    try {
        render::LoadedScene missing("no-such-file.glb");
    } catch (const scene::InputError& e) {
        refused = std::string(e.what()).find("no-such-file.glb") != std::string::npos;
    }
    std::printf("cuberille %s: %s %dx%d, %zu pixels drawn, %llu triangles set up\n", libraryVersion(), name.c_str(),
                first.image.width, first.image.height, differentFromCorner,
                (unsigned long long)first.stats.counters.trianglesSetUp);
    const bool ok = first.image.width == 96 && first.image.height == 54 && pixels.size() == 96 * 54 * 4 &&
                    differentFromCorner > 100 && pixels == again && refused;
    if (!ok) std::fprintf(stderr, "thumbnail: the installed library did not render as expected\n");
    return ok ? 0 : 1;
}
