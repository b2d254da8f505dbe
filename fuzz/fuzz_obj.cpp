// OBJ meshes with their MTL libraries (scene/obj_loader.h). The input is written beside itself as
// `fuzz.mtl`, so an input that says `mtllib fuzz.mtl` is parsed as both: one corpus reaches both
// parsers and the materials' use by faces.
#include "fuzz/fuzz_support.h"
#include "scene/obj_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("cuberille-fuzz-obj-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "fuzz.mtl", std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
    fuzz::acceptingInputErrors(
        [&] { scene::parseObj(std::string(fuzz::bytesOf(data, size)), "fuzz.obj", dir, fuzz::ignoreWarning); });
    return 0;
}
