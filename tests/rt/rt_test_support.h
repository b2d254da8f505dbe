#pragma once
// Meshes made in code for the rt/ tests: random triangle soups, an axis-aligned lattice (whose
// faces, edges and vertices lie exactly on box planes: the hard cases for traversal) and a
// closed sphere (where a watertight test must never let a ray through); and the structural
// check every built or refitted tree must pass.

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "rt/bvh.h"
#include "rt/bvh_build.h"
#include "rt/ray.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt::testing {

struct OwnedMesh {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    TriangleMeshView view() const { return {positions, indices}; }
};

/// n independent triangles, centres uniform in [-1, 1]^3, edges up to `size` long.
inline OwnedMesh randomSoup(uint32_t n, uint32_t seed, float size = 0.2f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    OwnedMesh m;
    for (uint32_t i = 0; i < n; ++i) {
        const glm::vec3 c(unit(rng), unit(rng), unit(rng));
        for (int k = 0; k < 3; ++k) {
            m.positions.push_back(c + size * glm::vec3(unit(rng), unit(rng), unit(rng)));
            m.indices.push_back(uint32_t(m.positions.size() - 1));
        }
    }
    return m;
}

/// The faces of an n x n x n lattice of unit cubes with integer corners in [0, n]: every face
/// two triangles, shared vertices, every coordinate an integer.
inline OwnedMesh cubeLattice(int n) {
    OwnedMesh m;
    auto vertex = [&](int x, int y, int z) { return uint32_t((z * (n + 1) + y) * (n + 1) + x); };
    for (int z = 0; z <= n; ++z)
        for (int y = 0; y <= n; ++y)
            for (int x = 0; x <= n; ++x) m.positions.push_back(glm::vec3(float(x), float(y), float(z)));
    auto quad = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
        m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    };
    for (int z = 0; z <= n; ++z)
        for (int y = 0; y <= n; ++y)
            for (int x = 0; x <= n; ++x) {
                if (x < n && y < n) quad(vertex(x, y, z), vertex(x + 1, y, z), vertex(x + 1, y + 1, z), vertex(x, y + 1, z));
                if (y < n && z < n) quad(vertex(x, y, z), vertex(x, y + 1, z), vertex(x, y + 1, z + 1), vertex(x, y, z + 1));
                if (x < n && z < n) quad(vertex(x, y, z), vertex(x, y, z + 1), vertex(x + 1, y, z + 1), vertex(x + 1, y, z));
            }
    return m;
}

/// The rays that break naive traversal of cubeLattice(4), whose every coordinate is an integer:
/// starting in, running along and passing through box and cell faces, triangle edges and
/// vertices, with +0 and -0 components; each also with its axes rotated. f(ray) for each.
template <class F>
void forEachLatticeRay(F&& f) {
    const float nz = -0.0f;
    const glm::vec3 directions[] = {{0, 0, 1},  {0, 0, -1}, {1, 0, 0},   {0, nz, 1}, {nz, 0, -1}, {nz, nz, 1},
                                    {1, 1, 0},  {1, 1, 1},  {-1, -1, 1}, {1, 2, 0},  {0, 1, nz},  {0.5f, 0, 1}};
    for (int x = -1; x <= 5; ++x)
        for (int y = -1; y <= 5; ++y)
            for (const float fx : {0.0f, 0.5f})
                for (const float fy : {0.0f, 0.5f})
                    for (const float z : {-1.0f, 0.0f, 2.0f, 2.5f})
                        for (const glm::vec3& d : directions) {
                            const glm::vec3 o(float(x) + fx, float(y) + fy, z);
                            f(Ray{o, d});
                            f(Ray{{o.z, o.x, o.y}, {d.z, d.x, d.y}});
                        }
}

/// `count` random rays in [-1.5, 1.5]^3 with random directions, every third a finite segment
/// (shadow-ray style) and every fifth starting past a tMin; f(ray) for each.
template <class F>
void forEachRandomRay(uint32_t seed, int count, F&& f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.5f, 1.5f), range(0.0f, 3.0f);
    for (int i = 0; i < count; ++i) {
        Ray ray{{unit(rng), unit(rng), unit(rng)}, {unit(rng), unit(rng), unit(rng)}};
        if (i % 3 == 0) ray.tMax = range(rng);
        if (i % 5 == 0) ray.tMin = range(rng) * 0.1f;
        f(ray);
    }
}

/// `count` rays leaving random points on the mesh's triangles in random directions, each with
/// tMin 0 (it may hit its own triangle at t = 0) and 1e-4; f(ray) for each.
template <class F>
void forEachRayFromSurface(const TriangleMeshView& m, uint32_t seed, int count, F&& f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f), weight(0.0f, 1.0f);
    for (int i = 0; i < count; ++i) {
        const uint32_t t = uint32_t(rng() % m.triangleCount());
        float a = weight(rng), b = weight(rng);
        if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
        const glm::vec3 p = m.vertex(t, 0) + a * (m.vertex(t, 1) - m.vertex(t, 0)) + b * (m.vertex(t, 2) - m.vertex(t, 0));
        const glm::vec3 d(unit(rng), unit(rng), unit(rng));
        for (const float tMin : {0.0f, 1e-4f}) f(Ray{p, d, tMin});
    }
}

/// Rays that leave a surface from within a few ulps of it, on either side, with tMin 0: what an
/// occlusion or shadow ray started without its offset is. The origin is a point of a triangle
/// with each coordinate moved up to `ulps` representable floats either way, the direction a
/// random one on the side of the triangle's plane it leaves by (about its normal, and grazing).
/// For such a ray the watertight test may round its own triangle's t, a few ulps below zero, to
/// +-0 or a few ulps above: the case where the hit's definition must hold for every traversal.
template <class F>
void forEachRayLeavingNearASurface(const TriangleMeshView& m, uint32_t seed, int count, int ulps, F&& f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f), weight(0.0f, 1.0f);
    std::uniform_int_distribution<int> steps(-ulps, ulps);
    for (int i = 0; i < count; ++i) {
        const uint32_t t = uint32_t(rng() % m.triangleCount());
        float a = weight(rng), b = weight(rng);
        if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
        const glm::vec3 e1 = m.vertex(t, 1) - m.vertex(t, 0), e2 = m.vertex(t, 2) - m.vertex(t, 0);
        glm::vec3 p = m.vertex(t, 0) + a * e1 + b * e2;
        for (int axis = 0; axis < 3; ++axis)
            for (int s = steps(rng); s != 0; s += s > 0 ? -1 : 1)
                p[axis] = std::nextafter(p[axis], s > 0 ? INFINITY : -INFINITY);
        const glm::vec3 n = glm::normalize(glm::cross(e1, e2)) * (rng() % 2 ? 1.0f : -1.0f);
        glm::vec3 d(unit(rng), unit(rng), unit(rng));
        d += n * (i % 4 == 0 ? 0.05f : 1.0f);  // a quarter of them grazing
        if (glm::dot(d, n) < 0.0f) d -= 2.0f * glm::dot(d, n) * n;
        f(Ray{p, d, 0.0f});
    }
}

/// An axis-aligned box's twelve triangles, appended to m.
inline void addBox(OwnedMesh& m, glm::vec3 lo, glm::vec3 hi) {
    const uint32_t b = uint32_t(m.positions.size());
    for (int c = 0; c < 8; ++c) m.positions.push_back({(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
    const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) m.indices.insert(m.indices.end(), {b + f[0], b + f[1], b + f[2], b + f[0], b + f[2], b + f[3]});
}

inline void append(OwnedMesh& m, const OwnedMesh& other) {
    const uint32_t b = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), other.positions.begin(), other.positions.end());
    for (uint32_t i : other.indices) m.indices.push_back(b + i);
}

/// A closed UV sphere of radius r around c.
inline OwnedMesh uvSphere(int rings, int segments, glm::vec3 c = glm::vec3(0.0f), float r = 1.0f) {
    OwnedMesh m;
    m.positions.push_back(c + glm::vec3(0, 0, r));
    for (int i = 1; i < rings; ++i) {
        const float theta = 3.14159265f * float(i) / float(rings);
        for (int j = 0; j < segments; ++j) {
            const float phi = 2.0f * 3.14159265f * float(j) / float(segments);
            m.positions.push_back(c + r * glm::vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
        }
    }
    m.positions.push_back(c + glm::vec3(0, 0, -r));
    const uint32_t south = uint32_t(m.positions.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
    for (int j = 0; j < segments; ++j) m.indices.insert(m.indices.end(), {0u, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i < rings - 1; ++i)
        for (int j = 0; j < segments; ++j)
            m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    for (int j = 0; j < segments; ++j) m.indices.insert(m.indices.end(), {south, ring(rings - 1, j + 1), ring(rings - 1, j)});
    return m;
}

/// Checks every structural invariant of `bvh` over `mesh`.
inline void expectWellFormed(const Bvh& bvh, const TriangleMeshView& mesh) {
    const size_t n = mesh.triangleCount();
    ASSERT_EQ(bvh.primitiveIndices.size(), n);
    if (n == 0) return;
    EXPECT_EQ(bvh.nodes[0].box(), meshBounds(mesh)) << "the root box is the mesh's";
    std::vector<int> seen(n, 0);
    size_t leaves = 0;
    for (uint32_t i = 0; i < bvh.nodes.size(); ++i) {
        const BvhNode& node = bvh.nodes[i];
        EXPECT_LE(bvh.depth[i], kMaxBvhDepth);
        if (node.isLeaf()) {
            ++leaves;
            EXPECT_EQ(node.first, bvh.subtreeFirst[i]);
            EXPECT_EQ(node.primitiveCount, bvh.subtreeCount[i]);
            Aabb tight;
            for (uint32_t k = node.first; k < node.first + node.primitiveCount; ++k) {
                const uint32_t triangle = bvh.primitiveIndices[k];
                ++seen[triangle];
                EXPECT_TRUE(node.box().contains(mesh.triangleBounds(triangle))) << "triangle " << triangle << " leaf " << i;
                tight.grow(mesh.triangleBounds(triangle));
            }
            EXPECT_EQ(node.box(), tight) << "leaf " << i << " is not tight";
            continue;
        }
        ASSERT_LT(node.first + 1, bvh.nodes.size());
        const BvhNode &left = bvh.nodes[node.first], &right = bvh.nodes[node.first + 1];
        EXPECT_TRUE(node.box().contains(left.box())) << "node " << i;
        EXPECT_TRUE(node.box().contains(right.box())) << "node " << i;
        EXPECT_EQ(node.box(), merged(left.box(), right.box())) << "node " << i << " is not tight";
        EXPECT_EQ(bvh.depth[node.first], bvh.depth[i] + 1);
        EXPECT_EQ(bvh.subtreeFirst[node.first], bvh.subtreeFirst[i]);
        EXPECT_EQ(bvh.subtreeFirst[node.first + 1], bvh.subtreeFirst[i] + bvh.subtreeCount[node.first]);
        EXPECT_EQ(bvh.subtreeCount[node.first] + bvh.subtreeCount[node.first + 1], bvh.subtreeCount[i]);
        EXPECT_GE(bvh.buildAreaRatio[i], 0.0f);
    }
    EXPECT_EQ(bvh.nodes.size(), 2 * leaves - 1) << "a full binary tree";
    for (size_t t = 0; t < n; ++t) EXPECT_EQ(seen[t], 1) << "triangle " << t << " in " << seen[t] << " leaves";
}

}  // namespace cuberille::rt::testing
