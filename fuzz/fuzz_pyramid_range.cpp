// Range files (lod/pyramid_ranges.h), what a distributed voxelization's range tasks hand to the
// join: header, block table, the level-S copies the join builds the levels above from; then the
// accepted range is joined into a .cvox and a voxel export, so what the reader lets through must
// be safe to simplify, link and copy. The model is a 128^3 one (two levels); the plan's split
// level is the one the file's header states when the pyramid has it.
#include <sstream>

#include "fuzz/fuzz_support.h"
#include "lod/pyramid_ranges.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const fuzz::InputFile file(data, size, ".cvxr");
    voxel::VoxelModel header;
    header.grid.resolution = 128;
    header.blockSize = 64;
    lod::PyramidRangePlan plan;
    plan.levels = 2;
    plan.splitLevel = size > 8 && data[8] == 1 ? 1 : 0;
    fuzz::acceptingInputErrors([&] {
        const lod::PyramidRangeJoin join(header, {file.path()}, {}, plan);
        std::ostringstream cvox, text;
        join.write(cvox, &text);
    });
    return 0;
}
