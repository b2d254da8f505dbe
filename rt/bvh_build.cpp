#include "rt/bvh_build.h"

#include <algorithm>
#include <array>

#include "raster/parallel.h"

namespace cuberille::rt {
namespace {

// Ranges with more primitives than this build their two halves as parallel tasks.
constexpr uint32_t kParallelSubtreePrimitives = 4096;
// Reductions over a node's primitives run in fixed chunks of this many (fixed, so the combined
// result does not depend on the thread count) when the node has at least two chunks.
constexpr uint32_t kChunkPrimitives = 16384;
constexpr int kMaxBins = 64;
// Past this depth every split halves the primitives by count, so no input (exponentially spaced
// triangles, say) can make the tree deeper than this plus log2(count) <= 32: kMaxBvhDepth holds.
constexpr int kHeuristicDepthLimit = 48;
static_assert(kHeuristicDepthLimit + 33 <= kMaxBvhDepth);

struct RangeBounds {
    Aabb box;      // of the primitives
    Aabb centres;  // of their centroids
};

// A node as the recursion makes it. A node over primitives [b, e) owns the slots
// [slot, slot + 2(e-b) - 1): itself at `slot`, its left child's region next, its right child's
// after. Slots are known before the children exist, so the halves build in parallel without
// sharing a counter; layout() then packs the tree depth-first.
struct BuildNode {
    Aabb box;
    uint32_t first = 0, count = 0;
    uint32_t left = 0, right = 0;  // slots; equal (0) for a leaf
};

struct SplitChoice {
    int axis = -1;
    int lastLeftBin = -1;  // primitives in bins [0, lastLeftBin] go left
    float cost = 0.0f;
};

class Builder {
public:
    Builder(const TriangleMeshView& mesh, const BvhBuildOptions& options) : mesh_(mesh), options_(options) {}

    Bvh build() {
        const uint32_t n = uint32_t(mesh_.triangleCount());
        Bvh bvh;
        bvh.method = options_.method;
        if (n == 0) return bvh;
        boxes_.resize(n);
        centres_.resize(n);
        indices_.resize(n);
        raster::parallelFor((n + kChunkPrimitives - 1) / kChunkPrimitives, [&](size_t chunk) {
            const uint32_t b = uint32_t(chunk) * kChunkPrimitives, e = std::min(n, b + kChunkPrimitives);
            for (uint32_t i = b; i < e; ++i) {
                boxes_[i] = mesh_.triangleBounds(i);
                centres_[i] = boxes_[i].centre();
                indices_[i] = i;
            }
        });
        nodes_.resize(2 * size_t(n) - 1);
        buildNode(0, 0, n, 0);
        layout(bvh);
        return bvh;
    }

private:
    void buildNode(uint32_t slot, uint32_t b, uint32_t e, int depth) {
        const RangeBounds bounds = rangeBounds(b, e);
        BuildNode& node = nodes_[slot];
        node.box = bounds.box;
        node.first = b;
        node.count = e - b;
        const uint32_t mid = split(b, e, bounds, depth);
        if (mid == b) return;  // a leaf
        node.left = slot + 1;
        node.right = slot + 2 * (mid - b);
        auto left = [&] { buildNode(slot + 1, b, mid, depth + 1); };
        auto right = [&] { buildNode(slot + 2 * (mid - b), mid, e, depth + 1); };
        if (e - b > kParallelSubtreePrimitives) {
            raster::parallelInvoke(left, right);
        } else {
            left();
            right();
        }
    }

    /// Partitions [b, e) and returns where the right half starts, or b for a leaf.
    uint32_t split(uint32_t b, uint32_t e, const RangeBounds& bounds, int depth) {
        const uint32_t n = e - b;
        if (n <= 1) return b;
        const glm::vec3 extent = bounds.centres.extent();
        const bool coincident = extent.x <= 0.0f && extent.y <= 0.0f && extent.z <= 0.0f;
        const uint32_t leafLimit = options_.method == BvhBuildMethod::SpatialMedian ? options_.medianLeafPrimitives
                                                                                     : options_.maxLeafPrimitives;
        if (depth >= kHeuristicDepthLimit) return n <= leafLimit ? b : splitByCount(b, e, bounds.centres);
        if (options_.method == BvhBuildMethod::SpatialMedian) {
            if (n <= options_.medianLeafPrimitives) return b;
            return coincident ? b + n / 2 : splitAtSpatialMedian(b, e, bounds.centres);
        }
        // All centroids in one point: no plane separates them. Cap the leaf size by count.
        if (coincident) return n > options_.maxLeafPrimitives ? b + n / 2 : b;
        const SplitChoice choice = bestSahSplit(b, e, bounds);
        const float leafCost = float(n) * bounds.box.surfaceArea();
        if (n <= options_.maxLeafPrimitives && !(choice.cost < leafCost)) return b;
        return partitionByBin(b, e, bounds.centres, choice);
    }

    // ---- surface area heuristic over binned centroids --------------------------------------

    struct Bins {
        std::array<std::array<uint32_t, kMaxBins>, 3> count{};
        std::array<std::array<Aabb, kMaxBins>, 3> box{};
    };

    /// Which bin a centroid falls in along each axis: one multiply, the scale computed once per
    /// node (binning and partitioning use this same arithmetic, so they agree exactly).
    struct Binning {
        glm::vec3 lo, scale;
        int bins;
        bool axisUsable[3];

        Binning(const Aabb& centres, int binCount) : lo(centres.lo), bins(binCount) {
            for (int a = 0; a < 3; ++a) {
                axisUsable[a] = centres.hi[a] > centres.lo[a];
                scale[a] = axisUsable[a] ? float(bins) / (centres.hi[a] - centres.lo[a]) : 0.0f;
            }
        }
        int bin(const glm::vec3& c, int axis) const {
            return std::clamp(int((c[axis] - lo[axis]) * scale[axis]), 0, bins - 1);
        }
    };

    Binning binningFor(const Aabb& centres) const { return Binning(centres, std::clamp(options_.sahBins, 2, kMaxBins)); }

    void binRange(uint32_t b, uint32_t e, const Binning& binning, Bins& bins) const {
        for (uint32_t i = b; i < e; ++i) {
            const uint32_t p = indices_[i];
            const Aabb& box = boxes_[p];
            const glm::vec3& c = centres_[p];
            for (int axis = 0; axis < 3; ++axis) {
                if (!binning.axisUsable[axis]) continue;
                const int bin = binning.bin(c, axis);
                ++bins.count[axis][bin];
                bins.box[axis][bin].grow(box);
            }
        }
    }

    SplitChoice bestSahSplit(uint32_t b, uint32_t e, const RangeBounds& bounds) const {
        const int binCount = std::clamp(options_.sahBins, 2, kMaxBins);
        Bins bins;
        const uint32_t chunks = (e - b + kChunkPrimitives - 1) / kChunkPrimitives;
        const Binning binning = binningFor(bounds.centres);
        if (chunks < 2) {
            binRange(b, e, binning, bins);
        } else {
            std::vector<Bins> partial(chunks);
            raster::parallelFor(chunks, [&](size_t c) {
                const uint32_t cb = b + uint32_t(c) * kChunkPrimitives;
                binRange(cb, std::min(e, cb + kChunkPrimitives), binning, partial[c]);
            });
            for (const Bins& p : partial)  // in chunk order: exact anyway (counts, min, max)
                for (int axis = 0; axis < 3; ++axis)
                    for (int i = 0; i < binCount; ++i) {
                        bins.count[axis][i] += p.count[axis][i];
                        bins.box[axis][i].grow(p.box[axis][i]);
                    }
        }
        // Cost of splitting after bin i, unnormalised (times the node's area):
        // traversal x area(node) + area(left) x count(left) + area(right) x count(right).
        SplitChoice best;
        const float nodeArea = bounds.box.surfaceArea();
        for (int axis = 0; axis < 3; ++axis) {
            if (!(bounds.centres.hi[axis] > bounds.centres.lo[axis])) continue;
            std::array<float, kMaxBins> rightCost{};
            Aabb right;
            uint32_t rightCount = 0;
            for (int i = binCount - 1; i > 0; --i) {
                right.grow(bins.box[axis][i]);
                rightCount += bins.count[axis][i];
                rightCost[i] = right.surfaceArea() * float(rightCount);
            }
            Aabb left;
            uint32_t leftCount = 0;
            for (int i = 0; i < binCount - 1; ++i) {
                left.grow(bins.box[axis][i]);
                leftCount += bins.count[axis][i];
                if (leftCount == 0 || leftCount == e - b) continue;
                const float cost = options_.traversalCost * nodeArea + left.surfaceArea() * float(leftCount) + rightCost[i + 1];
                if (best.axis < 0 || cost < best.cost) best = {axis, i, cost};
            }
        }
        return best;
    }

    uint32_t partitionByBin(uint32_t b, uint32_t e, const Aabb& centres, const SplitChoice& choice) {
        const Binning binning = binningFor(centres);
        auto goesLeft = [&](uint32_t p) { return binning.bin(centres_[p], choice.axis) <= choice.lastLeftBin; };
        return uint32_t(std::partition(indices_.begin() + b, indices_.begin() + e, goesLeft) - indices_.begin());
    }

    // ---- spatial median ----------------------------------------------------------------------

    uint32_t splitAtSpatialMedian(uint32_t b, uint32_t e, const Aabb& centres) {
        const glm::vec3 extent = centres.extent();
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
        const float middle = centres.centre()[axis];
        auto below = [&](uint32_t p) { return centres_[p][axis] < middle; };
        const uint32_t mid = uint32_t(std::partition(indices_.begin() + b, indices_.begin() + e, below) - indices_.begin());
        if (mid != b && mid != e) return mid;
        return splitByCount(b, e, centres);  // rounding put every centroid on one side
    }

    /// The object median along the centroid box's longest axis (ties by triangle id): always
    /// halves, whatever the positions.
    uint32_t splitByCount(uint32_t b, uint32_t e, const Aabb& centres) {
        const glm::vec3 extent = centres.extent();
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
        const uint32_t half = b + (e - b) / 2;
        std::nth_element(indices_.begin() + b, indices_.begin() + half, indices_.begin() + e, [&](uint32_t p, uint32_t q) {
            return centres_[p][axis] < centres_[q][axis] || (centres_[p][axis] == centres_[q][axis] && p < q);
        });
        return half;
    }

    // ---- reductions and layout -----------------------------------------------------------------

    RangeBounds boundsOfChunk(uint32_t b, uint32_t e) const {
        RangeBounds r;
        for (uint32_t i = b; i < e; ++i) {
            r.box.grow(boxes_[indices_[i]]);
            r.centres.grow(centres_[indices_[i]]);
        }
        return r;
    }

    RangeBounds rangeBounds(uint32_t b, uint32_t e) const {
        const uint32_t chunks = (e - b + kChunkPrimitives - 1) / kChunkPrimitives;
        if (chunks < 2) return boundsOfChunk(b, e);
        std::vector<RangeBounds> partial(chunks);
        raster::parallelFor(chunks, [&](size_t c) {
            const uint32_t cb = b + uint32_t(c) * kChunkPrimitives;
            partial[c] = boundsOfChunk(cb, std::min(e, cb + kChunkPrimitives));
        });
        RangeBounds r;
        for (const RangeBounds& p : partial) {
            r.box.grow(p.box);
            r.centres.grow(p.centres);
        }
        return r;
    }

    /// Packs the build slots depth-first, a node's children side by side.
    void layout(Bvh& bvh) {
        size_t nodeCount = 0;
        for (const BuildNode& n : nodes_) nodeCount += n.count > 0;  // unused slots have count 0
        bvh.nodes.resize(nodeCount);
        bvh.subtreeFirst.resize(nodeCount);
        bvh.subtreeCount.resize(nodeCount);
        bvh.depth.resize(nodeCount);
        bvh.buildAreaRatio.assign(nodeCount, 1.0f);
        struct Pending {
            uint32_t slot, index;
            uint8_t depth;
        };
        std::vector<Pending> stack{{0, 0, 0}};
        uint32_t next = 1;
        while (!stack.empty()) {
            const Pending p = stack.back();
            stack.pop_back();
            const BuildNode& b = nodes_[p.slot];
            BvhNode& node = bvh.nodes[p.index];
            node.setBox(b.box);
            bvh.subtreeFirst[p.index] = b.first;
            bvh.subtreeCount[p.index] = b.count;
            bvh.depth[p.index] = p.depth;
            bvh.height = std::max(bvh.height, int(p.depth));
            if (b.left == b.right) {
                node.first = b.first;
                node.primitiveCount = b.count;
                continue;
            }
            node.first = next;
            node.primitiveCount = 0;
            bvh.buildAreaRatio[p.index] = areaRatio(b.box, nodes_[b.left].box, nodes_[b.right].box);
            stack.push_back({b.right, next + 1, uint8_t(p.depth + 1)});
            stack.push_back({b.left, next, uint8_t(p.depth + 1)});
            next += 2;
        }
        bvh.primitiveIndices = std::move(indices_);
        gatherLeafVertices(bvh, mesh_);
    }

    const TriangleMeshView& mesh_;
    BvhBuildOptions options_;
    std::vector<Aabb> boxes_;
    std::vector<glm::vec3> centres_;
    std::vector<uint32_t> indices_;
    std::vector<BuildNode> nodes_;
};

}  // namespace

Bvh buildBvh(const TriangleMeshView& mesh, const BvhBuildOptions& options) { return Builder(mesh, options).build(); }

void gatherLeafVertices(Bvh& bvh, const TriangleMeshView& mesh) {
    const size_t n = bvh.primitiveIndices.size();
    bvh.leafVertices.resize(3 * n);
    raster::parallelFor((n + kChunkPrimitives - 1) / kChunkPrimitives, [&](size_t chunk) {
        for (size_t i = chunk * kChunkPrimitives; i < std::min(n, (chunk + 1) * kChunkPrimitives); ++i)
            for (int c = 0; c < 3; ++c) bvh.leafVertices[3 * i + c] = mesh.vertex(bvh.primitiveIndices[i], c);
    });
}

Aabb meshBounds(const TriangleMeshView& mesh) {
    Aabb b;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) b.grow(mesh.triangleBounds(t));
    return b;
}

}  // namespace cuberille::rt
