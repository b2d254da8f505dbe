// Geometry streams (.cgs, voxel/geometry_stream.h): headers walked without decompressing, every
// chunk read and decompressed (sizes checked against the file before allocating).
#include "fuzz/fuzz_support.h"
#include "voxel/mesh_view.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".cgs");
    fuzz::acceptingInputErrors([&] {
        const auto view = voxel::openMeshView(file.path(), fuzz::ignoreWarning);
        for (size_t i = 0; i < view->chunkCount(); ++i) view->readChunk(i);
    });
    return 0;
}
