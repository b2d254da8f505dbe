// Camera path keyframe files (lod/camera_path.h), then sampled along the path.
#include "fuzz/fuzz_support.h"
#include "lod/camera_path.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".path");
    fuzz::acceptingInputErrors([&] {
        const lod::CameraPath path = lod::CameraPath::fromFile(file.path());
        scene::Camera base;
        for (float t : {0.0f, 0.3f, 1.0f}) (void)path.at(t, base).clipFromWorld(1.5f);
    });
    return 0;
}
