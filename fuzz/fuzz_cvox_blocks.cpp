// Voxel models (.cvox, voxel/cvox_file.h), the reader alone: the header, the block table, then
// every block loaded part by part, the way streaming reads it (lod/streaming_blocks.h). Without
// fuzz_cvox's drawing an input costs microseconds instead of milliseconds, so the fuzzer explores
// the table and payload checks far deeper in the same time. What the reader hands back must keep
// its promises: the counts the table states, every voxel inside its block.
#include <cstdlib>

#include "fuzz/fuzz_support.h"
#include "voxel/cvox_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".cvox");
    fuzz::acceptingInputErrors([&] {
        const voxel::CvoxReader reader(file.path());
        const voxel::VoxelModel& layout = reader.layout();
        for (size_t b = 0; b < reader.blockCount(); ++b) {
            const voxel::VoxelBlock voxels = reader.load(b, voxel::CvoxReader::kVoxels);
            const voxel::VoxelBlock triangles = reader.load(b, voxel::CvoxReader::kTriangles);
            const voxel::VoxelBlock& stated = layout.blocks[b];
            if (voxels.voxels.size() != stated.layoutVoxels || voxels.normals.size() != voxels.voxels.size() ||
                voxels.colors.size() != voxels.voxels.size() || triangles.triangles.size() != stated.layoutTriangles)
                std::abort();
            for (const uint32_t v : voxels.voxels) {
                const glm::uvec3 p = voxel::voxelPositionInBlock(v);
                if (p.x >= layout.blockSize || p.y >= layout.blockSize || p.z >= layout.blockSize) std::abort();
            }
        }
    });
    return 0;
}
