#include "voxel/octree_voxelizer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <numeric>
#include <unordered_map>
#include <stdexcept>

#include <tbb/enumerable_thread_specific.h>

#include "raster/clock.h"
#include "raster/parallel.h"
#include "voxel/exact_overlap.h"
#include "voxel/intersection_targets.h"
#include "voxel/morton.h"
#include "voxel/packing.h"
#include "voxel/voxel_octree.h"

namespace cuberille::voxel {
namespace {

/// What a leaf needs of the triangle a piece came from.
struct TriangleContext {
    glm::dvec3 normal[3];
    glm::dvec3 color[3];
    glm::dvec3 geometricNormal{0.0};  // unit, or zero for a degenerate triangle
    uint8_t faceMask = 0;
    uint64_t index = 0;  // in the whole mesh: chunk order, then order in the chunk
    LatticeTriangle lattice;  // the same corners, exactly, for leaves rounding cannot decide
};

/// The fan triangles of the pieces one thread found in one block, each with its sort key
/// (source triangle index << 8 | fan index): sorting by it at emission makes the order independent
/// of which thread found which piece.
struct BlockTriangles {
    std::vector<uint64_t> keys;
    std::vector<SourceTriangle> triangles;
};
using BlockTriangleBuckets = std::unordered_map<uint64_t, BlockTriangles>;  // by block Morton code

uint8_t activeFaces(const glm::dvec3& n, double epsilon) {
    uint8_t m = 0;
    if (n.x > epsilon) m |= kFacePosX;
    if (n.x < -epsilon) m |= kFaceNegX;
    if (n.y > epsilon) m |= kFacePosY;
    if (n.y < -epsilon) m |= kFaceNegY;
    if (n.z > epsilon) m |= kFacePosZ;
    if (n.z < -epsilon) m |= kFaceNegZ;
    return m;
}

template <class T>
T interpolate(const T (&v)[3], const glm::dvec2& bary) {
    return v[0] * (1.0 - bary.x - bary.y) + v[1] * bary.x + v[2] * bary.y;
}

/// One thread's octree and the source-triangle pieces it found.
class TreeBuilder {
public:
    TreeBuilder(const VoxelGrid& grid, const VoxelizeOptions& options, bool colors)
        : grid_(grid),
          options_(options),
          tree_(log2OfPowerOfTwo(grid.resolution), colors),
          leafDepth_(tree_.leafDepth()),
          blockDepth_(std::max(0, leafDepth_ - log2OfPowerOfTwo(kBlockSize))) {}

    void insertChunk(const GeometryChunk& chunk, uint64_t firstTriangle) {
        for (size_t t = 0; t < chunk.triangleCount(); ++t) {
            TriangleContext tri;
            tri.index = firstTriangle + t;
            TrianglePiece piece;
            piece.count = 3;
            glm::dvec3 p[3];
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = chunk.indices[3 * t + k];
                // Snapped to the 2^-40 lattice: the clipping below and the exact leaf test then see
                // the very same triangle.
                const glm::dvec3 unit = glm::clamp(grid_.toUnitCube(chunk.positions[v]), glm::dvec3(0.0), glm::dvec3(1.0));
                for (int a = 0; a < 3; ++a) {
                    tri.lattice.v[k][a] = std::llround(unit[a] * kLatticeScale);
                    p[k][a] = double(tri.lattice.v[k][a]) / kLatticeScale;
                }
                tri.normal[k] = glm::dvec3(chunk.normals[v]);
                tri.color[k] = chunk.hasColors() ? glm::dvec3(chunk.colors[v]) : glm::dvec3(1.0);
                piece.v[k].position = p[k];
            }
            piece.v[0].bary = {0.0, 0.0};
            piece.v[1].bary = {1.0, 0.0};
            piece.v[2].bary = {0.0, 1.0};
            const glm::dvec3 g = glm::cross(p[1] - p[0], p[2] - p[0]);
            const double len = glm::length(g);
            tri.geometricNormal = len > 0.0 ? g / len : glm::dvec3(0.0);
            tri.faceMask = activeFaces(tri.geometricNormal, options_.activeFaceEpsilon);
            tri_ = &tri;
            descend(VoxelOctree::root(), 0, glm::uvec3(0), piece);
        }
    }

    VoxelOctree& tree() { return tree_; }
    BlockTriangleBuckets& blockTriangles() { return blockTriangles_; }
    uint64_t leafPieces() const { return leafPieces_; }
    uint64_t exactTests() const { return exactTests_; }
    double readMs = 0;

private:
    /// Walks a piece down from `node` (at `depth`, covering grid cell `cell` of that depth) to the
    /// leaves. A piece inside one child moves down in place; one that straddles mid-planes is split
    /// axis by axis, and each part recurses.
    void descend(uint32_t node, int depth, glm::uvec3 cell, TrianglePiece& piece) {
        for (;;) {
            if (depth == blockDepth_ && options_.keepSourceTriangles) recordBlockPiece(cell, piece);
            if (depth == leafDepth_) {
                accumulateLeaf(node, cell, piece);
                return;
            }
            glm::dvec3 lo, hi;
            piece.bounds(lo, hi);
            int octant = 0;
            bool single = true;
            for (int axis = 0; axis < 3 && single; ++axis) {
                if (hi[axis] < 0.5 - kTouchEpsilon) continue;
                if (lo[axis] > 0.5 + kTouchEpsilon) octant |= 1 << axis;
                else single = false;
            }
            if (!single) break;
            for (int i = 0; i < piece.count; ++i)
                for (int axis = 0; axis < 3; ++axis) {
                    double& c = piece.v[i].position[axis];
                    c = (octant >> axis & 1) ? c * 2.0 - 1.0 : c * 2.0;
                }
            node = tree_.childOf(node, depth, octant);
            cell = cell * 2u + glm::uvec3(octant & 1, octant >> 1 & 1, octant >> 2 & 1);
            ++depth;
        }
        TrianglePiece xs[2], ys[2], zs[2];
        splitPieceAtMidPlane(piece, 0, xs[0], xs[1]);
        for (int ix = 0; ix < 2; ++ix) {
            if (xs[ix].count == 0) continue;
            splitPieceAtMidPlane(xs[ix], 1, ys[0], ys[1]);
            for (int iy = 0; iy < 2; ++iy) {
                if (ys[iy].count == 0) continue;
                splitPieceAtMidPlane(ys[iy], 2, zs[0], zs[1]);
                for (int iz = 0; iz < 2; ++iz) {
                    if (zs[iz].count == 0) continue;
                    const int octant = ix | iy << 1 | iz << 2;
                    descend(tree_.childOf(node, depth, octant), depth + 1, cell * 2u + glm::uvec3(ix, iy, iz), zs[iz]);
                }
            }
        }
    }

    /// The clipped piece of one triangle in one voxel (in voxel units, so its area is in voxels²)
    /// adds its area-weighted attributes; the face mask and targets are unions. A piece that only
    /// grazes the voxel counts only if the exact test says the triangle touches it.
    void accumulateLeaf(uint32_t leaf, const glm::uvec3& cell, const TrianglePiece& piece) {
        if (pieceOnlyGrazesCube(piece)) {
            ++exactTests_;
            if (!latticeTriangleTouchesVoxel(tri_->lattice, cell, leafDepth_)) return;
        }
        ++leafPieces_;
        glm::dvec2 bary;
        const double weight = pieceAreaAndCentroid(piece, bary) * kLeafWeightScale + kContactWeight;
        glm::dvec3 n = interpolate(tri_->normal, bary);
        const double len = glm::length(n);
        n = len > 0.0 ? n / len : tri_->geometricNormal;
        LeafSums& s = tree_.leaf(leaf);
        for (int k = 0; k < 3; ++k) s.normal[k] += roundToInt64(weight * n[k]);
        s.weight += roundToInt64(weight);
        s.faceMask |= tri_->faceMask;
        if (tree_.withColors()) {
            const glm::dvec3 c = interpolate(tri_->color, bary);
            LeafColorSums& cs = tree_.leafColor(leaf);
            for (int k = 0; k < 3; ++k) cs.rgb[k] += roundToInt64(weight * c[k]);
        }
        // Targets are tested only for the separability asked for, and only until one is met.
        switch (options_.separability) {
            case Separability::Conservative: break;
            case Separability::Six:
                if (!(s.targets & kMetCrosshair) && pieceMeetsCrosshair(piece)) s.targets |= kMetCrosshair;
                break;
            case Separability::TwentySix:
                if (!(s.targets & (kMetDiagonals | kMetCrosshair))) {
                    if (pieceMeetsDiagonals(piece)) s.targets |= kMetDiagonals;
                    else if (pieceMeetsCrosshair(piece)) s.targets |= kMetCrosshair;
                }
                break;
        }
    }

    /// The piece at the block depth, in model units, as a fan of triangles.
    void recordBlockPiece(const glm::uvec3& block, const TrianglePiece& piece) {
        if (piece.count < 3) return;  // a point or segment of contact: nothing to draw
        const double blockExtent = grid_.extent / double(1u << blockDepth_);
        auto vertex = [&](int i, SourceTriangle& out, int slot) {
            const glm::dvec3 p = grid_.origin + (glm::dvec3(block) + piece.v[i].position) * blockExtent;
            out.position[slot] = glm::vec3(p);
            const glm::dvec3 n = interpolate(tri_->normal, piece.v[i].bary);
            const double len = glm::length(n);
            out.normal[slot] = packNormal1010102(glm::vec3(len > 0.0 ? n / len : tri_->geometricNormal));
            out.color[slot] = packSrgba8(glm::vec3(interpolate(tri_->color, piece.v[i].bary)));
        };
        const uint64_t morton = mortonOf(block);
        if (!lastBucket_ || lastBlock_ != morton) {
            lastBucket_ = &blockTriangles_[morton];
            lastBlock_ = morton;
        }
        for (int i = 1; i + 1 < piece.count; ++i) {
            SourceTriangle t;
            vertex(0, t, 0);
            vertex(i, t, 1);
            vertex(i + 1, t, 2);
            lastBucket_->keys.push_back(tri_->index << 8 | uint64_t(i - 1));
            lastBucket_->triangles.push_back(t);
        }
    }

    const VoxelGrid& grid_;
    const VoxelizeOptions& options_;
    VoxelOctree tree_;
    int leafDepth_, blockDepth_;
    const TriangleContext* tri_ = nullptr;
    BlockTriangleBuckets blockTriangles_;
    BlockTriangles* lastBucket_ = nullptr;  // the bucket of the block last recorded into
    uint64_t lastBlock_ = 0;
    uint64_t leafPieces_ = 0, exactTests_ = 0;
};

/// Gathers the kept voxels into blocks straight from the per-thread trees, without merging them
/// first (Chajdas merges the trees, section 3.1.1; here the merge happens per block, in parallel):
/// each tree's top levels are walked once to list its block subtrees; subtrees of the same block
/// are grouped (Morton order of the block, then tree order); each block is then filled on its own
/// task by reading its subtrees' leaves in Morton order and summing the leaves they share.
/// Integer sums make the result the same as a merged tree's, for any thread count.
class BlockEmitter {
public:
    BlockEmitter(std::vector<const VoxelOctree*> trees, const VoxelizeOptions& options,
                 std::vector<BlockTriangleBuckets*> triangles, VoxelModel& model, VoxelizeStats& stats)
        : trees_(std::move(trees)), options_(options), triangles_(std::move(triangles)), model_(model), stats_(stats),
          leafDepth_(trees_[0]->leafDepth()), blockDepth_(std::max(0, leafDepth_ - log2OfPowerOfTwo(kBlockSize))),
          withColors_(trees_[0]->withColors()) {}

    void run() {
        std::vector<SubtreeRef> subtrees;
        for (uint32_t t = 0; t < trees_.size(); ++t) listBlocks(t, VoxelOctree::root(), 0, glm::uvec3(0), subtrees);
        std::sort(subtrees.begin(), subtrees.end(), [](const SubtreeRef& a, const SubtreeRef& b) {
            return a.morton != b.morton ? a.morton < b.morton : a.tree < b.tree;
        });
        std::vector<std::pair<size_t, size_t>> groups;  // [first, last) of each block's subtrees
        for (size_t i = 0; i < subtrees.size();) {
            size_t j = i + 1;
            while (j < subtrees.size() && subtrees[j].morton == subtrees[i].morton) ++j;
            groups.push_back({i, j});
            i = j;
        }
        std::vector<VoxelBlock> blocks(groups.size());
        std::vector<uint64_t> touched(groups.size(), 0);  // conservative voxels per block
        raster::parallelFor(groups.size(), [&](size_t g) {
            fillBlock(&subtrees[groups[g].first], groups[g].second - groups[g].first, blocks[g], touched[g]);
        });
        for (size_t i = 0; i < blocks.size(); ++i) {
            stats_.conservativeVoxels += touched[i];
            if (blocks[i].voxels.empty() && blocks[i].triangles.empty()) continue;
            stats_.voxels += blocks[i].voxels.size();
            stats_.sourceTriangles += blocks[i].triangles.size();
            model_.blocks.push_back(std::move(blocks[i]));
        }
    }

private:
    struct SubtreeRef {
        uint64_t morton;
        uint32_t tree, node;
        glm::uvec3 cell;
    };
    /// One leaf of one tree, with its position's Morton code inside the block.
    struct LeafRef {
        uint32_t localMorton;
        uint32_t tree, leaf;
        glm::uvec3 local;
    };

    void listBlocks(uint32_t t, uint32_t node, int depth, const glm::uvec3& cell, std::vector<SubtreeRef>& out) const {
        if (depth == blockDepth_) {
            out.push_back({mortonOf(cell), t, node, cell});
            return;
        }
        for (int octant = 0; octant < 8; ++octant)
            if (const uint32_t c = trees_[t]->existingChild(node, octant))
                listBlocks(t, c, depth + 1, cell * 2u + glm::uvec3(octant & 1, octant >> 1 & 1, octant >> 2 & 1), out);
    }

    void fillBlock(const SubtreeRef* subtrees, size_t count, VoxelBlock& b, uint64_t& touched) const {
        b.coord = subtrees[0].cell;
        b.tightMin = glm::uvec3(model_.blockSize);
        std::vector<LeafRef> leaves;
        for (size_t s = 0; s < count; ++s) gather(subtrees[s].tree, subtrees[s].node, blockDepth_, glm::uvec3(0), leaves);
        // Each tree's leaves came in Morton order; with several trees, order them all (tree order
        // breaks ties) so shared leaves sit side by side.
        if (count > 1)
            std::sort(leaves.begin(), leaves.end(), [](const LeafRef& x, const LeafRef& y) {
                return x.localMorton != y.localMorton ? x.localMorton < y.localMorton : x.tree < y.tree;
            });
        for (size_t i = 0; i < leaves.size();) {
            LeafSums sums = trees_[leaves[i].tree]->leaf(leaves[i].leaf);
            LeafColorSums colors = withColors_ ? trees_[leaves[i].tree]->leafColor(leaves[i].leaf) : LeafColorSums{};
            size_t j = i + 1;
            for (; j < leaves.size() && leaves[j].localMorton == leaves[i].localMorton; ++j) {
                const LeafSums& o = trees_[leaves[j].tree]->leaf(leaves[j].leaf);
                for (int k = 0; k < 3; ++k) sums.normal[k] += o.normal[k];
                sums.weight += o.weight;
                sums.faceMask |= o.faceMask;
                sums.targets |= o.targets;
                if (withColors_)
                    for (int k = 0; k < 3; ++k) colors.rgb[k] += trees_[leaves[j].tree]->leafColor(leaves[j].leaf).rgb[k];
            }
            emitVoxel(sums, colors, leaves[i].local, b, touched);
            i = j;
        }
        gatherTriangles(subtrees[0].morton, b);
        if (b.voxels.empty()) b.tightMin = glm::uvec3(0);
    }

    /// Every thread's fan triangles for the block, in source triangle order. Each bucket is
    /// emptied as it is used (its own block's entry only, so blocks filled in parallel never touch
    /// the same entry, and the maps are not restructured), so the peak holds them once.
    void gatherTriangles(uint64_t morton, VoxelBlock& b) const {
        std::vector<uint64_t> keys;
        std::vector<SourceTriangle> found;
        for (BlockTriangleBuckets* buckets : triangles_) {
            const auto it = buckets->find(morton);
            if (it == buckets->end()) continue;
            keys.insert(keys.end(), it->second.keys.begin(), it->second.keys.end());
            found.insert(found.end(), it->second.triangles.begin(), it->second.triangles.end());
            std::vector<uint64_t>().swap(it->second.keys);
            std::vector<SourceTriangle>().swap(it->second.triangles);
        }
        std::vector<uint32_t> order(keys.size());
        std::iota(order.begin(), order.end(), 0u);
        std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return keys[x] < keys[y]; });
        b.triangles.reserve(order.size());
        for (uint32_t i : order) b.triangles.push_back(found[i]);
    }

    void gather(uint32_t t, uint32_t node, int depth, const glm::uvec3& local, std::vector<LeafRef>& out) const {
        if (depth == leafDepth_) {
            out.push_back({uint32_t(mortonOf(local)), t, node, local});
            return;
        }
        for (int octant = 0; octant < 8; ++octant)
            if (const uint32_t c = trees_[t]->existingChild(node, octant))
                gather(t, c, depth + 1, local * 2u + glm::uvec3(octant & 1, octant >> 1 & 1, octant >> 2 & 1), out);
    }

    void emitVoxel(const LeafSums& s, const LeafColorSums& c, const glm::uvec3& local, VoxelBlock& b,
                   uint64_t& touched) const {
        if (s.weight == 0) return;  // reached only by pieces the exact test turned away
        ++touched;
        const bool keep = options_.separability == Separability::Conservative ||
                          (options_.separability == Separability::Six && (s.targets & kMetCrosshair)) ||
                          (options_.separability == Separability::TwentySix && s.targets != 0);
        if (!keep) return;
        const glm::dvec3 n(double(s.normal[0]), double(s.normal[1]), double(s.normal[2]));
        const double len = glm::length(n);
        b.voxels.push_back(packVoxel(local.x, local.y, local.z, s.faceMask));
        b.normals.push_back(packNormal1010102(len > 0.0 ? glm::vec3(n / len) : glm::vec3(0.0f)));
        if (withColors_) {
            const double w = double(s.weight);
            b.colors.push_back(packSrgba8(glm::vec3(double(c.rgb[0]) / w, double(c.rgb[1]) / w, double(c.rgb[2]) / w)));
        } else {
            b.colors.push_back(0xFFFFFFFFu);
        }
        b.tightMin = glm::min(b.tightMin, local);
        b.tightMax = glm::max(b.tightMax, local);
    }

    std::vector<const VoxelOctree*> trees_;
    const VoxelizeOptions& options_;
    std::vector<BlockTriangleBuckets*> triangles_;
    VoxelModel& model_;
    VoxelizeStats& stats_;
    int leafDepth_, blockDepth_;
    bool withColors_;
};

}  // namespace

VoxelGrid gridFor(const MeshView& mesh, uint32_t resolution) {
    glm::vec3 lo, hi;
    mesh.bounds(lo, hi);
    if (lo.x > hi.x) lo = hi = glm::vec3(0.0f);
    return VoxelGrid::fitting(glm::dvec3(lo), glm::dvec3(hi), resolution);
}

VoxelModel voxelizeMesh(const MeshView& mesh, const VoxelizeOptions& options, VoxelizeStats* statsOut) {
    if (!isValidResolution(options.resolution))
        throw std::invalid_argument("resolution " + std::to_string(options.resolution) +
                                    " is not a power of two from 2 to 65536");
    VoxelizeStats stats;
    VoxelModel model;
    model.grid = options.grid ? *options.grid : gridFor(mesh, options.resolution);
    model.grid.resolution = options.resolution;
    model.blockSize = std::min(kBlockSize, options.resolution);
    model.separability = options.separability;
    model.hasColors = mesh.hasColors();

    // Each chunk's first triangle's index in the whole mesh: the sort key that makes source
    // triangles come out in one order whatever thread read which chunk.
    std::vector<uint64_t> firstTriangle(mesh.chunkCount() + 1, 0);
    for (size_t i = 0; i < mesh.chunkCount(); ++i) firstTriangle[i + 1] = firstTriangle[i] + mesh.chunkInfo(i).triangleCount;
    stats.chunks = mesh.chunkCount();
    stats.triangles = firstTriangle.back();

    tbb::enumerable_thread_specific<std::unique_ptr<TreeBuilder>> builders;
    std::atomic<size_t> done{0};
    std::mutex progressMutex;
    double t0 = raster::nowMs();
    raster::parallelFor(mesh.chunkCount(), [&](size_t chunk) {
        std::unique_ptr<TreeBuilder>& b = builders.local();
        if (!b) b = std::make_unique<TreeBuilder>(model.grid, options, model.hasColors);
        const double r0 = raster::nowMs();
        const GeometryChunk c = mesh.readChunk(chunk);
        b->readMs += raster::nowMs() - r0;
        b->insertChunk(c, firstTriangle[chunk]);
        const size_t n = ++done;
        if (options.progress) {
            std::lock_guard<std::mutex> lock(progressMutex);
            options.progress(n, mesh.chunkCount());
        }
    });
    stats.rasterizeMs = raster::nowMs() - t0;

    t0 = raster::nowMs();
    std::vector<TreeBuilder*> trees;
    for (auto& b : builders)
        if (b) trees.push_back(b.get());
    stats.threads = int(trees.size());
    std::vector<BlockTriangleBuckets*> triangles;
    for (TreeBuilder* b : trees) {
        stats.octreeBytes += b->tree().reservedBytes();
        stats.leafPieces += b->leafPieces();
        stats.exactTests += b->exactTests();
        stats.readMs += b->readMs;
        triangles.push_back(&b->blockTriangles());
    }
    // The trees are merged block by block while emitting (BlockEmitter), not here.
    stats.mergeMs = raster::nowMs() - t0;

    t0 = raster::nowMs();
    if (!trees.empty()) {
        std::vector<const VoxelOctree*> octrees;
        for (TreeBuilder* b : trees) octrees.push_back(&b->tree());
        BlockEmitter(std::move(octrees), options, std::move(triangles), model, stats).run();
    }
    stats.blocks = model.blocks.size();
    stats.emitMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
    return model;
}

}  // namespace cuberille::voxel
