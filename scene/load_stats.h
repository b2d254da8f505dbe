#pragma once
// What loading a scene did, for --stats: the per-vertex work done on the CPU before the
// pipeline runs. Static meshes skin and morph nothing, and these say so.

#include <cstdint>

namespace cuberille::scene {

struct LoadStats {
    uint64_t verticesSkinned = 0;  // vertices blended by joint matrices (glTF skins)
    uint64_t verticesMorphed = 0;  // vertices with at least one non-zero morph target weight
    uint64_t texturesDecoded = 0;  // (image, colour space) pairs turned into mip chains
};

}  // namespace cuberille::scene
