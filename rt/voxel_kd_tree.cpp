// The voxel kD tree (Chajdas 2015, §5.4.1): binned SAH splits at integer planes, traversed front
// to back with a short stack and restarts (Algorithm 5.1).
//
//   trace: clip the ray to the root cell
//     interior: where the ray meets the split plane decides the children: only the near one (it
//               leaves the cell first), only the far one (crossed before the cell), or the near
//               one now and the far one pushed with the rest of the segment
//     leaf:     the shared voxel test; a null leaf (an empty side) is a leaf with nothing to test
//     pop:      as the BVH's; a restart descends from the root with the segment past the last leaf

#include <algorithm>
#include <array>

#include "rt/voxel_traversal.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

namespace {

/// A guard on the tree's depth, so the full stack never overflows: a node this deep becomes a
/// leaf whatever it holds (no scene of 16-bit voxels has come near it; binned SAH halves a node's
/// voxels every level or two).
constexpr int kMaxKdDepth = VoxelTraversal::kFullStack - 4;

int coordinate(const VoxelCoord& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

/// Surface area of the cell [lo, hi) (halved: only ratios matter).
double halfArea(const glm::ivec3& lo, const glm::ivec3& hi) {
    const glm::dvec3 e = glm::dvec3(hi - lo);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

}  // namespace

struct VoxelKdBuilder {
    VoxelLeaves& data;

    /// The subtree over data.voxels[first, first + count) in the cell [lo, hi), into `out`.
    uint32_t build(VoxelSubtree<VoxelKdNode>& out, uint32_t first, uint32_t count, const glm::ivec3& lo, const glm::ivec3& hi,
                   int depth) {
        if (count == 0) return VoxelNodeRef::kNull;
        if (count <= kVoxelLeafSize || depth >= kMaxKdDepth) return out.leaf(first, count);
        const VoxelCoord* begin = data.voxels.data() + first;
        const VoxelBounds tight = voxelBounds({begin, count});
        const glm::ivec3 &tightLo = tight.lo, &tightHi = tight.hi;
        // Bin along the voxels' longest axis (it spans at least two: the voxels are distinct).
        const glm::ivec3 extent = tightHi - tightLo;
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        // Candidate planes: the 31 inner bin boundaries, and the tight bounds where they cut empty
        // space off the cell (a split that leaves one side empty, a null leaf).
        std::vector<int> planes;
        if (tightLo[axis] > lo[axis]) planes.push_back(tightLo[axis]);
        for (int k = 1; k < VoxelKdTree::kBins; ++k) {
            const int p = tightLo[axis] + int(int64_t(extent[axis]) * k / VoxelKdTree::kBins);
            if (p > tightLo[axis] && p < tightHi[axis] && (planes.empty() || planes.back() != p)) planes.push_back(p);
        }
        if (tightHi[axis] < hi[axis]) planes.push_back(tightHi[axis]);
        // Voxels below each plane: a histogram over the gaps between planes, then prefix sums.
        std::vector<uint32_t> binCount(planes.size() + 1, 0);
        for (uint32_t i = 0; i < count; ++i) {
            const int c = coordinate(begin[i], axis);
            binCount[std::upper_bound(planes.begin(), planes.end(), c) - planes.begin()] += 1;
        }
        // SAH with a voxel's cost one wherever it lies (§5.4.1): area-weighted counts of the two
        // child cells. The lowest cost wins; ties go to the lower plane.
        size_t bestPlane = 0;
        double bestCost = std::numeric_limits<double>::infinity();
        uint32_t below = 0;
        for (size_t j = 0; j < planes.size(); ++j) {
            below += binCount[j];
            glm::ivec3 belowHi = hi, aboveLo = lo;
            belowHi[axis] = aboveLo[axis] = planes[j];
            const double cost = halfArea(lo, belowHi) * below + halfArea(aboveLo, hi) * (count - below);
            if (cost < bestCost) {
                bestCost = cost;
                bestPlane = j;
            }
        }
        int split = planes[bestPlane], splitAxis = axis;
        // Cutting empty space off the cell on the other two axes, too: kD cells are not tight,
        // and a leaf's cell that reaches far past its voxels is entered by rays that hit none of
        // them (on the bunny at 256³ this halved the leaves a shadow ray visits).
        for (int a = 0; a < 3; ++a) {
            if (a == axis) continue;
            for (int side = 0; side < 2; ++side) {
                const int p = side ? tightHi[a] : tightLo[a];
                if (p <= lo[a] || p >= hi[a]) continue;
                glm::ivec3 belowHi = hi, aboveLo = lo;
                belowHi[a] = aboveLo[a] = p;
                const double cost = side ? halfArea(lo, belowHi) * count : halfArea(aboveLo, hi) * count;
                if (cost < bestCost) {
                    bestCost = cost;
                    split = p;
                    splitAxis = a;
                }
            }
        }
        const uint32_t nBelow = partitionBelow(data, first, count, splitAxis, split);
        const uint32_t node = uint32_t(out.nodes.size());
        out.nodes.push_back({{0, 0}, uint16_t(split), uint8_t(splitAxis)});
        glm::ivec3 belowHi = hi, aboveLo = lo;
        belowHi[splitAxis] = aboveLo[splitAxis] = split;
        uint32_t refs[2];
        buildChildren(out, 2, count >= kParallelBuildVoxels, [&](int c, VoxelSubtree<VoxelKdNode>& into) {
            return c == 0 ? build(into, first, nBelow, lo, belowHi, depth + 1)
                          : build(into, first + nBelow, count - nBelow, aboveLo, hi, depth + 1);
        }, refs);
        out.nodes[node].child[0] = refs[0];
        out.nodes[node].child[1] = refs[1];
        return node;
    }
};

VoxelKdTree::VoxelKdTree(std::span<const VoxelCoord> voxels) : VoxelTreeStorage(voxels) {
    if (voxels.empty()) return;
    const VoxelBounds b = voxelBounds(voxels);  // the root cell
    VoxelSubtree<VoxelKdNode> tree;
    const uint32_t root = VoxelKdBuilder{data_}.build(tree, 0, uint32_t(voxels.size()), b.lo, b.hi, 0);
    adopt(std::move(tree.nodes), std::move(tree.leaves), root, glm::vec3(b.lo), glm::vec3(b.hi));
}

VoxelHit VoxelKdTree::trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters,
                            VoxelStepTrace* steps) const {
    VoxelStepCounts counts{.trace = steps};
    VoxelHit best;
    float sceneEnter, sceneExit;
    if (!enterRoot(ray, &sceneEnter, &sceneExit)) return counts.finish(best, data_, counters);

    VoxelTraversalStack<VoxelSegmentEntry> stack(how.stackEntries);
    uint32_t ref = root_;
    float enter = sceneEnter, exit = sceneExit;  // the segment of the node at hand
    for (;;) {
        // Down to a leaf. The near child is the lower one unless the ray runs toward lower values.
        while (ref != VoxelNodeRef::kNull && !VoxelNodeRef::isLeaf(ref)) {
            counts.step(kInteriorStep);
            const Node& n = nodes_[ref];
            const int a = n.axis;
            if (ray.parallel[a]) {  // half-open slabs: a ray in the plane belongs above it
                ref = n.child[ray.origin[a] < float(n.split) ? 0 : 1];
                continue;
            }
            const float crossing = ray.planeT(a, float(n.split));
            const int near = ray.farSide[a];
            if (crossing <= enter) {
                ref = n.child[1 - near];
            } else if (crossing >= exit) {
                ref = n.child[near];
            } else {
                stack.push({n.child[1 - near], crossing, exit});
                ref = n.child[near];
                exit = crossing;
            }
        }
        counts.step(kLeafStep);
        if (ref != VoxelNodeRef::kNull && testLeaf(data_, VoxelNodeRef::index(ref), ray, how.anyHit, best, counts))
            return counts.finish(best, data_, counters);
        const float finishedTo = exit;
        if (VoxelSegmentEntry next; stack.popStartingBy(best.t, &next)) {
            ref = next.ref;
            enter = next.enter;
            exit = next.exit;
            continue;
        }
        if (!stack.takeLost() || finishedTo >= sceneExit || finishedTo > best.t)
            return counts.finish(best, data_, counters);
        ++counts.restarts;
        ref = root_;
        enter = finishedTo;
        exit = sceneExit;
    }
}

}  // namespace cuberille::rt
