// PLY meshes, ASCII and binary (scene/ply_loader.h): counts in the header are checked against the
// bytes before anything is allocated.
#include "fuzz/fuzz_support.h"
#include "scene/ply_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    fuzz::acceptingInputErrors([&] { scene::parsePly(fuzz::bytesOf(data, size), "fuzz.ply"); });
    return 0;
}
