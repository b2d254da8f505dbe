// Edge adjacency against a brute-force count of every edge's users: shared edges are exactly
// the ones two triangles use in opposite directions, whatever the vertex indices say.

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "rt/mesh_adjacency.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

/// A unit cube, each face with its own four vertices (as a mesh split for UVs is).
OwnedMesh cubeWithSplitFaces() {
    OwnedMesh m;
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        const uint32_t b = uint32_t(m.positions.size());
        for (const int c : f) m.positions.push_back({float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)});
        m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
    }
    return m;
}

TEST(MeshAdjacency, AClosedCubeSplitAtEveryFaceIsOneSheet) {
    const OwnedMesh cube = cubeWithSplitFaces();
    const MeshAdjacency a = buildMeshAdjacency(cube.view());
    EXPECT_EQ(a.positionCount, 8u);
    EXPECT_EQ(a.shared.size(), 18u);  // 12 triangles, 36 directed edges, all paired
    EXPECT_TRUE(a.openPositions.empty());
}

TEST(MeshAdjacency, BoundariesFansOfThreeAndFlippedWindingAreOpen) {
    OwnedMesh quad;
    quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1.0f}};
    quad.indices = {0, 1, 2, 0, 2, 3};
    MeshAdjacency a = buildMeshAdjacency(quad.view());
    EXPECT_EQ(a.shared.size(), 1u);
    EXPECT_EQ(a.openPositions.size(), 4u);  // the border

    OwnedMesh fan = quad;  // a third triangle on the diagonal 0-2
    fan.indices.insert(fan.indices.end(), {0, 4, 2});
    a = buildMeshAdjacency(fan.view());
    EXPECT_TRUE(a.shared.empty());

    OwnedMesh flipped = quad;
    flipped.indices = {0, 1, 2, 0, 3, 2};  // the second triangle wound the other way
    a = buildMeshAdjacency(flipped.view());
    EXPECT_TRUE(a.shared.empty());
}

TEST(MeshAdjacency, MatchesBruteForceEdgeCounts) {
    // A sphere with some triangles repeated (non-manifold edges), some dropped (holes) and its
    // vertices duplicated at random (seams).
    OwnedMesh m = testing::uvSphere(12, 24);
    std::mt19937 rng(5);
    OwnedMesh mesh;
    mesh.positions = m.positions;
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
        const uint32_t r = rng() % 16;
        if (r == 0) continue;  // a hole
        for (int c = 0; c < 3; ++c) {
            uint32_t v = m.indices[3 * t + c];
            if (rng() % 4 == 0) {  // a split vertex at the same position
                mesh.positions.push_back(m.positions[v]);
                v = uint32_t(mesh.positions.size() - 1);
            }
            mesh.indices.push_back(v);
        }
        if (r == 1) mesh.indices.insert(mesh.indices.end(), m.indices.begin() + 3 * t, m.indices.begin() + 3 * t + 3);
    }
    const MeshAdjacency a = buildMeshAdjacency(mesh.view());

    // Brute force: every undirected edge (by position) with the directed uses it has.
    auto key = [&](uint32_t v) { return std::tuple(mesh.positions[v].x, mesh.positions[v].y, mesh.positions[v].z); };
    using Point = decltype(key(0));
    std::map<std::pair<Point, Point>, std::vector<std::pair<Point, Point>>> uses;
    for (size_t t = 0; t < mesh.indices.size() / 3; ++t)
        for (int c = 0; c < 3; ++c) {
            const Point p = key(mesh.indices[3 * t + c]), q = key(mesh.indices[3 * t + (c + 1) % 3]);
            uses[std::minmax(p, q)].push_back({p, q});
        }
    size_t shared = 0;
    std::set<Point> open;
    for (const auto& [edge, directed] : uses) {
        if (directed.size() == 2 && edge.first != edge.second && directed[0].first == directed[1].second &&
            directed[0].second == directed[1].first)
            ++shared;
        else
            open.insert(edge.first), open.insert(edge.second);
    }
    EXPECT_EQ(a.shared.size(), shared);
    EXPECT_EQ(a.openPositions.size(), open.size());
    EXPECT_GT(shared, 0u);
    EXPECT_GT(open.size(), 0u);
    for (const MeshAdjacency::SharedEdge& e : a.shared) {  // the two triangles do hold the edge
        int found = 0;
        for (const uint32_t t : {e.first, e.second})
            for (int c = 0; c < 3; ++c) found += a.positionId[mesh.indices[3 * t + c]] == e.from || a.positionId[mesh.indices[3 * t + c]] == e.to;
        EXPECT_EQ(found, 4);
    }
}

}  // namespace
}  // namespace cuberille::rt
