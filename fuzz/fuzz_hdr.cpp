// Radiance .hdr environment maps (scene/environment_map.h): the header, the resolution line and
// run-length or flat scanlines, every count checked; the pixels' least size is checked against
// the file before anything is allocated.
#include "fuzz/fuzz_support.h"
#include "scene/environment_map.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".hdr");
    fuzz::acceptingInputErrors([&] { scene::readEquirectangularImage(file.path()); });
    return 0;
}
