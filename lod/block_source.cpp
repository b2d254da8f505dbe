#include "lod/block_source.h"

#include <algorithm>
#include <cstring>

#include "voxel/packing.h"

namespace cuberille::lod {
namespace {

/// A vertex's bits, for merging identical ones.
struct VertexKey {
    uint32_t bits[5];
    auto operator<=>(const VertexKey&) const = default;
};

VertexKey keyOf(const voxel::SourceTriangle& t, int v) {
    VertexKey k;
    std::memcpy(k.bits, &t.position[v], 12);
    k.bits[3] = t.normal[v];
    k.bits[4] = t.color[v];
    return k;
}

}  // namespace

IndexedTriangles indexSourceTriangles(std::span<const voxel::SourceTriangle> triangles) {
    IndexedTriangles out;
    const size_t n = triangles.size() * 3;
    // Sort corner numbers by their vertex bits (ties by number), so equal vertices sit together;
    // each run gets the id of its first corner's order of use.
    std::vector<uint32_t> corners(n);
    for (uint32_t c = 0; c < n; ++c) corners[c] = c;
    auto key = [&](uint32_t c) { return keyOf(triangles[c / 3], int(c % 3)); };
    std::sort(corners.begin(), corners.end(), [&](uint32_t a, uint32_t b) {
        const VertexKey ka = key(a), kb = key(b);
        return ka != kb ? ka < kb : a < b;
    });
    std::vector<uint32_t> representative(n);  // corner -> the first corner with its bits
    for (size_t i = 0; i < n; ++i)
        representative[corners[i]] = (i > 0 && key(corners[i]) == key(corners[i - 1])) ? representative[corners[i - 1]]
                                                                                          : corners[i];
    std::vector<uint32_t> vertexOf(n, UINT32_MAX);
    out.indices.resize(n);
    for (uint32_t c = 0; c < n; ++c) {
        uint32_t& id = vertexOf[representative[c]];
        if (id == UINT32_MAX) {
            const voxel::SourceTriangle& t = triangles[c / 3];
            const int v = int(c % 3);
            id = uint32_t(out.positions.size());
            out.positions.push_back(t.position[v]);
            out.normals.push_back(voxel::unpackNormal1010102(t.normal[v]));
            out.colors.push_back(voxel::unpackSrgba8Rgb(t.color[v]));
        }
        out.indices[c] = id;
    }
    return out;
}

ModelBlocks::ModelBlocks(voxel::VoxelModel model) : model_(std::move(model)), triangles_(model_.blocks.size()) {}

bool ModelBlocks::acquire(uint32_t block, BlockParts part) {
    voxel::VoxelBlock& b = model_.blocks[block];
    if ((part & BlockParts::kTriangles) && !b.triangles.empty()) {
        triangles_[block] = indexSourceTriangles(b.triangles);
        b.layoutTriangles = uint32_t(b.triangles.size());
        b.triangles = {};  // drawn from the indexed form; the count stays in the layout
    }
    return true;
}

}  // namespace cuberille::lod
