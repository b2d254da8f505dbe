#include "rt/wide_bvh.h"

#include <algorithm>
#include <limits>

#include "raster/parallel.h"

namespace cuberille::rt {
namespace {

/// A binary subtree of at most four triangles becomes one leaf of the wide tree: one group, one
/// vector test for all of them, where the binary tree's small SAH leaves (about two triangles on
/// the dragon) would leave half the lanes empty and spend a box test on each. Every subtree's
/// triangles are one run of slots (rt/bvh.h), so the leaf is that run.
bool isWideLeaf(const Bvh& binary, uint32_t node) {
    return binary.nodes[node].isLeaf() || binary.subtreeCount[node] <= uint32_t(kTriangleGroupWidth);
}

/// A node's children as the collapse gathers them: binary node indices, in slot order.
struct Gathered {
    uint32_t node[kWideBvhWidth];
    int count = 0;
};

/// Open the binary node's two children, then keep opening the inner child of largest surface
/// area (the one a random ray most likely enters, so the one whose two boxes save the most box
/// tests: Wald et al. 2008, §3) until the node is full or holds only leaves. The opened child's
/// place goes to its first child and its second is appended, so the order is fixed by the tree.
Gathered gatherChildren(const Bvh& binary, uint32_t inner) {
    Gathered g;
    g.node[g.count++] = binary.nodes[inner].first;
    g.node[g.count++] = binary.nodes[inner].first + 1;
    while (g.count < kWideBvhWidth) {
        int widest = -1;
        float widestArea = -1.0f;
        for (int i = 0; i < g.count; ++i) {
            if (isWideLeaf(binary, g.node[i])) continue;
            const float area = binary.nodes[g.node[i]].box().surfaceArea();
            if (area > widestArea) widest = i, widestArea = area;  // the first on a tie
        }
        if (widest < 0) break;
        const uint32_t opened = g.node[widest];
        g.node[widest] = binary.nodes[opened].first;
        g.node[g.count++] = binary.nodes[opened].first + 1;
    }
    return g;
}

class Collapse {
public:
    Collapse(const Bvh& binary, WideBvh& wide) : binary_(binary), wide_(wide) {}

    /// Writes the wide node for the binary node's subtree (a binary leaf as the root: one child)
    /// and, depth-first, the wide nodes below it: their links and where each box and vertex comes
    /// from, and empty boxes and NaN vertices where a slot or lane is unused. The used boxes and
    /// vertices are copied afterwards by refreshWideBvh, the one place that copies them. Returns
    /// the wide node's index.
    uint32_t emit(uint32_t binaryNode, int depth) {
        wide_.height = std::max(wide_.height, depth);
        const uint32_t index = uint32_t(wide_.nodes.size());
        wide_.nodes.emplace_back();
        Gathered g;
        if (isWideLeaf(binary_, binaryNode))
            g.node[g.count++] = binaryNode;
        else
            g = gatherChildren(binary_, binaryNode);
        wide_.childSource.resize(wide_.childSource.size() + kWideBvhWidth, WideBvhNode::kNoChild);
        for (int i = 0; i < g.count; ++i) wide_.childSource[size_t(index) * kWideBvhWidth + size_t(i)] = g.node[i];
        WideBvhNode node{};
        constexpr float kInfinity = std::numeric_limits<float>::infinity();
        for (int i = 0; i < kWideBvhWidth; ++i) {
            node.child[i] = WideBvhNode::kNoChild;
            for (int axis = 0; axis < 3; ++axis) node.lo[axis][i] = kInfinity, node.hi[axis][i] = -kInfinity;
        }
        for (int i = 0; i < g.count; ++i) {
            if (isWideLeaf(binary_, g.node[i])) {
                node.child[i] = uint32_t(wide_.triangleGroups.size());
                node.leafGroups[i] = groupLeaf(binary_.subtreeFirst[g.node[i]], binary_.subtreeCount[g.node[i]]);
            }
        }
        // Children are emitted after the parent's slot exists, so the parent is written last.
        for (int i = 0; i < g.count; ++i)
            if (!isWideLeaf(binary_, g.node[i])) node.child[i] = emit(g.node[i], depth + 1);
        wide_.nodes[index] = node;
        return index;
    }

private:
    /// Appends groups for the leaf's triangles (slots first .. first+count-1 of the binary tree),
    /// four to a group in slot order: their ids and slots. Returns how many groups.
    uint32_t groupLeaf(uint32_t first, uint32_t count) {
        constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
        const uint32_t groups = (count + kTriangleGroupWidth - 1) / kTriangleGroupWidth;
        for (uint32_t g = 0; g < groups; ++g) {
            WideBvhTriangles& t = wide_.triangleGroups.emplace_back();
            for (int lane = 0; lane < kTriangleGroupWidth; ++lane) {
                const uint32_t k = g * kTriangleGroupWidth + uint32_t(lane);
                const bool used = k < count;
                t.triangle[lane] = used ? binary_.primitiveIndices[first + k] : WideBvhTriangles::kNoTriangle;
                wide_.laneSource.push_back(used ? first + k : WideBvhTriangles::kNoTriangle);
                for (int axis = 0; axis < 3; ++axis) t.a[axis][lane] = t.b[axis][lane] = t.c[axis][lane] = kNaN;
            }
        }
        return groups;
    }

    const Bvh& binary_;
    WideBvh& wide_;
};

}  // namespace

void refreshWideBvh(WideBvh& wide, const Bvh& binary) {
    // Every node and group is written from its own sources alone: chunks run in any order and
    // give the same tree. A new collapse is filled the same way. On two threads BrainStem's
    // refresh takes 0.56 ms, against 0.90-0.97 serial, beside its 0.9 ms refit (bvh_bench's
    // animation).
    constexpr size_t kChunk = 4096;
    raster::parallelFor((wide.nodes.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
        for (size_t n = chunk * kChunk; n < std::min(wide.nodes.size(), (chunk + 1) * kChunk); ++n)
            for (int i = 0; i < kWideBvhWidth; ++i) {
                const uint32_t source = wide.childSource[n * kWideBvhWidth + size_t(i)];
                if (source == WideBvhNode::kNoChild) continue;
                for (int axis = 0; axis < 3; ++axis) {
                    wide.nodes[n].lo[axis][i] = binary.nodes[source].lo[axis];
                    wide.nodes[n].hi[axis][i] = binary.nodes[source].hi[axis];
                }
            }
    });
    raster::parallelFor((wide.triangleGroups.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
        for (size_t g = chunk * kChunk; g < std::min(wide.triangleGroups.size(), (chunk + 1) * kChunk); ++g)
            for (int lane = 0; lane < kTriangleGroupWidth; ++lane) {
                const uint32_t slot = wide.laneSource[g * kTriangleGroupWidth + size_t(lane)];
                if (slot == WideBvhTriangles::kNoTriangle) continue;
                const glm::vec3* v = &binary.leafVertices[3 * size_t(slot)];
                WideBvhTriangles& t = wide.triangleGroups[g];
                for (int axis = 0; axis < 3; ++axis)
                    t.a[axis][lane] = v[0][axis], t.b[axis][lane] = v[1][axis], t.c[axis][lane] = v[2][axis];
            }
    });
}

WideBvh collapseToWideBvh(const Bvh& binary) {
    WideBvh wide;
    if (binary.empty()) return wide;
    // Hints, not bounds: about a quarter as many nodes as the binary tree's inner ones (four
    // children a node on random soups), and a group per four triangles and some.
    wide.nodes.reserve(binary.innerNodeCount() / 4 + 1);
    wide.triangleGroups.reserve(binary.primitiveIndices.size() / 3 + 1);
    Collapse(binary, wide).emit(0, 0);
    refreshWideBvh(wide, binary);
    return wide;
}

}  // namespace cuberille::rt
