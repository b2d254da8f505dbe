// Voxel models (.cvox, voxel/cvox_file.h): the header, the block table (counts, offsets, links)
// and every block's payload; then what was accepted is selected and drawn, so links and bounds
// the reader lets through must be safe to walk.
#include "fuzz/fuzz_support.h"
#include "lod/voxel_scene.h"
#include "voxel/cvox_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".cvox");
    fuzz::acceptingInputErrors([&] {
        lod::VoxelScene scene(voxel::readCvox(file.path()), 30.0f, 20.0f);
        raster::FramebufferDesc fb;
        fb.widthPixels = 48, fb.heightPixels = 32;
        raster::Pipeline p;
        lod::VoxelRenderOptions o;
        o.selection.pixelError = 0.0f;  // every level down to the finest: the whole table walked
        for (int frame = 0; frame < 2; ++frame) {
            p.beginFrame(fb);
            scene.draw(p, fb.widthPixels, fb.heightPixels, o);
            p.endFrame();
            scene.readOcclusion(p.stats());
        }
    });
    return 0;
}
