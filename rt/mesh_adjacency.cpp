#include "rt/mesh_adjacency.h"

#include <algorithm>
#include <bit>
#include <tuple>

namespace cuberille::rt {
namespace {

/// Per vertex index, an id shared by every vertex at the same position (+0 and -0 alike): ids
/// in order of the sorted positions, so the same mesh always gets the same ids.
uint32_t assignPositionIds(std::span<const glm::vec3> positions, std::vector<uint32_t>& id) {
    auto bits = [](float v) { return std::bit_cast<uint32_t>(v == 0.0f ? 0.0f : v); };
    using Key = std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>;  // x, y, z bits, then the index
    std::vector<Key> keys(positions.size());
    for (size_t i = 0; i < positions.size(); ++i)
        keys[i] = {bits(positions[i].x), bits(positions[i].y), bits(positions[i].z), uint32_t(i)};
    std::sort(keys.begin(), keys.end());  // keys are unique: the order is the same on any run
    id.assign(positions.size(), 0);
    uint32_t next = 0;
    for (size_t k = 0; k < keys.size(); ++k) {
        if (k > 0 && (std::get<0>(keys[k]) != std::get<0>(keys[k - 1]) || std::get<1>(keys[k]) != std::get<1>(keys[k - 1]) ||
                      std::get<2>(keys[k]) != std::get<2>(keys[k - 1])))
            ++next;
        id[std::get<3>(keys[k])] = next;
    }
    return positions.empty() ? 0 : next + 1;
}

}  // namespace

MeshAdjacency buildMeshAdjacency(const TriangleMeshView& mesh) {
    MeshAdjacency a;
    a.positionCount = assignPositionIds(mesh.positions, a.positionId);
    const size_t triangles = mesh.triangleCount();
    // Every directed edge, bucketed by its lower end (a counting sort, in triangle order): the
    // edges that can pair with one are in its bucket.
    std::vector<uint32_t> bucketStart(size_t(a.positionCount) + 1, 0);
    auto ends = [&](size_t t, int c) {
        return std::pair(a.positionId[mesh.indices[3 * t + c]], a.positionId[mesh.indices[3 * t + (c + 1) % 3]]);
    };
    for (size_t t = 0; t < triangles; ++t)
        for (int c = 0; c < 3; ++c) ++bucketStart[std::min(ends(t, c).first, ends(t, c).second) + 1];
    for (size_t i = 1; i < bucketStart.size(); ++i) bucketStart[i] += bucketStart[i - 1];
    std::vector<uint32_t> fill(bucketStart.begin(), bucketStart.end() - 1);
    std::vector<uint32_t> directed(triangles * 3);  // 3 t + c
    for (size_t t = 0; t < triangles; ++t)
        for (int c = 0; c < 3; ++c) directed[fill[std::min(ends(t, c).first, ends(t, c).second)]++] = uint32_t(3 * t + c);

    // Within a bucket, the edges sorted by their upper end: each run of equal ends is one
    // undirected edge, shared when it holds exactly two directed edges running opposite ways.
    std::vector<uint8_t> open(a.positionCount, 0);
    std::vector<std::pair<uint32_t, uint32_t>> bucket;  // (upper end, directed edge)
    for (uint32_t low = 0; low < a.positionCount; ++low) {
        bucket.clear();
        for (uint32_t i = bucketStart[low]; i < bucketStart[low + 1]; ++i) {
            const auto [from, to] = ends(directed[i] / 3, int(directed[i] % 3));
            bucket.emplace_back(std::max(from, to), directed[i]);
        }
        std::sort(bucket.begin(), bucket.end());
        for (size_t run = 0; run < bucket.size();) {
            size_t end = run + 1;
            while (end < bucket.size() && bucket[end].first == bucket[run].first) ++end;
            const uint32_t e0 = bucket[run].second, e1 = end - run == 2 ? bucket[run + 1].second : 0;
            const auto [from, to] = ends(e0 / 3, int(e0 % 3));
            if (end - run == 2 && from != to && ends(e1 / 3, int(e1 % 3)) == std::pair(to, from))
                a.shared.push_back({e0 / 3, e1 / 3, from, to});
            else
                open[from] = open[to] = 1;
            run = end;
        }
    }
    for (uint32_t p = 0; p < a.positionCount; ++p)
        if (open[p]) a.openPositions.push_back(p);
    return a;
}

}  // namespace cuberille::rt
