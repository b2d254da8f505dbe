// Partial voxelizations (voxel/partial_voxelization_file.h), the parts a distributed voxelization's
// workers hand to the merge: the header, every block's leaves and triangles; then what was accepted
// is merged, so positions and orders the reader lets through must be safe to finish into blocks.
#include "fuzz/fuzz_support.h"
#include "voxel/partial_voxelization_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".cvxp");
    fuzz::acceptingInputErrors([&] {
        // One part: adding a damaged part's sums to another's could overflow, which parts the
        // voxelizer writes cannot (their sums are bounded by its weights).
        std::vector<voxel::PartialVoxelization> parts;
        parts.push_back(voxel::readPartialVoxelization(file.path()));
        const voxel::VoxelModel m = voxel::mergePartialVoxelizations(std::move(parts));
        volatile size_t voxels = m.voxelCount();
        (void)voxels;
    });
    return 0;
}
