// .tri triangle lists (scene/tri_scene.h), parsed from text and then drawn: whatever the parser
// accepts, the rasterizer must draw (window-space coordinates far outside the frame included).
#include "fuzz/fuzz_support.h"
#include "raster/pipeline.h"
#include "scene/tri_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    fuzz::acceptingInputErrors([&] {
        const scene::TriScene s = scene::parseTriScene(std::string(fuzz::bytesOf(data, size)), "fuzz.tri");
        raster::FramebufferDesc fb;
        fb.widthPixels = fb.heightPixels = 64;
        fb.samples = 4;
        raster::Pipeline p;
        p.beginFrame(fb);
        p.draw(s.drawCall());
        p.endFrame();
    });
    return 0;
}
