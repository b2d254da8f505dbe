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

/// The faces of the other side of each axis: what a face mask becomes when the surface's normal
/// is reversed (+x and -x swap, and so on).
uint8_t mirroredFaces(uint8_t m) {
    static_assert(kFacePosX == 1 && kFaceNegX == 2 && kFacePosY == 4 && kFaceNegY == 8 && kFacePosZ == 16 && kFaceNegZ == 32);
    return uint8_t((m & 0x15u) << 1 | (m & 0x2Au) >> 1);
}

/// Which way a mesh is wound (the defect this undoes: docs/voxelization.md). Active faces and
/// normals are taken from the triangles as wound, outward for a counter-clockwise mesh; a mesh
/// wound the other way (a closed scan wound clockwise seen from outside, as
/// ../shared/data/scans/cyberware-horse is) voxelized inside out, its front voxels' active faces
/// on the inside, and its frames showed the inside of the far wall. The winding's sign is that of
/// the mesh's signed volume seen from a point c: T(c) = sum over triangles of (p0 - c) . N, with
/// N = (p1 - p0) x (p2 - p0) (six times the volume, by the divergence theorem). For a closed mesh
/// the N sum to zero and T does not depend on c; for an open surface it does, T(c) = T(o) -
/// (c - o) . sum N, and the surface is taken as wound inwards only when T is negative seen from
/// every corner of the grid's cube (so from every point in it): a sphere with a hole is, a flat
/// patch never is, whichever way either is wound.
///
/// Each triangle's terms (about the cube's centre o, in unit-cube coordinates) are scaled by
/// 2^kWindingBits and rounded to integers, so the sums have the same bits whatever thread or
/// process (partial voxelizations) added which triangles; a term under half a unit is lost, which
/// needs a triangle under 2^-49 of the cube's area.
constexpr int kWindingBits = 48;

void addWindingTerms(const glm::dvec3 (&p)[3], const glm::dvec3& n, WindingSums& sums) {
    const double scale = std::ldexp(1.0, kWindingBits);
    sums.volume += uint64_t(std::llround(glm::dot(p[0] - glm::dvec3(0.5), n) * scale));
    for (int a = 0; a < 3; ++a) sums.area[a] += uint64_t(std::llround(n[a] * scale));
}

/// A mesh wound inwards has its normals negated and its face masks mirrored when its blocks are
/// finished.
bool woundInwards(const WindingSums& sums) {
    const double volume = double(int64_t(sums.volume));
    const glm::dvec3 area(double(int64_t(sums.area[0])), double(int64_t(sums.area[1])), double(int64_t(sums.area[2])));
    // T at the corner where (c - o) . sum N is least: T is largest there.
    const double largest = volume + 0.5 * (std::abs(area.x) + std::abs(area.y) + std::abs(area.z));
    return largest < 0.0;
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
            addWindingTerms(p, g, winding_);
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
    /// The inserted triangles' winding terms, summed (wrapping: the same bits in any order).
    const WindingSums& winding() const { return winding_; }
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
    WindingSums winding_;
};

/// A block's voxels from its merged leaf sums: the voxels the separability keeps, with their
/// normals and colours, and its source triangles in key order. The last step of voxelizeMesh and of
/// mergePartialVoxelizations alike. `touched` counts the conservative voxels.
void finishBlock(const BlockPartial& p, Separability separability, bool withColors, uint32_t blockSize,
                 bool woundInwards, VoxelBlock& b, uint64_t& touched) {
    b.coord = p.coord;
    b.tightMin = glm::uvec3(blockSize);
    const double sign = woundInwards ? -1.0 : 1.0;  // the mesh's, so every voxel's normal turns alike
    for (size_t i = 0; i < p.leaves.size(); ++i) {
        const LeafSums& s = p.leaves[i];
        if (s.weight == 0) continue;  // reached only by pieces the exact test turned away
        ++touched;
        const bool keep = separability == Separability::Conservative ||
                          (separability == Separability::Six && (s.targets & kMetCrosshair)) ||
                          (separability == Separability::TwentySix && s.targets != 0);
        if (!keep) continue;
        const glm::uvec3 local = positionOfMorton(p.leafMorton[i]);
        const glm::dvec3 n(sign * double(s.normal[0]), sign * double(s.normal[1]), sign * double(s.normal[2]));
        const double len = glm::length(n);
        b.voxels.push_back(packVoxel(local.x, local.y, local.z, woundInwards ? mirroredFaces(s.faceMask) : s.faceMask));
        b.normals.push_back(packNormal1010102(len > 0.0 ? glm::vec3(n / len) : glm::vec3(0.0f)));
        if (withColors) {
            const LeafColorSums& c = p.colors[i];
            const double w = double(s.weight);
            b.colors.push_back(packSrgba8(glm::vec3(double(c.rgb[0]) / w, double(c.rgb[1]) / w, double(c.rgb[2]) / w)));
        } else {
            b.colors.push_back(0xFFFFFFFFu);
        }
        b.tightMin = glm::min(b.tightMin, local);
        b.tightMax = glm::max(b.tightMax, local);
    }
    b.triangles = p.triangles;
    if (b.voxels.empty()) b.tightMin = glm::uvec3(0);
}

/// Adds leaf `j` of `from` into `into`'s last leaf (the same voxel).
void addLeaf(BlockPartial& into, const BlockPartial& from, size_t j, bool withColors) {
    LeafSums& s = into.leaves.back();
    const LeafSums& o = from.leaves[j];
    for (int k = 0; k < 3; ++k) s.normal[k] += o.normal[k];
    s.weight += o.weight;
    s.faceMask |= o.faceMask;
    s.targets |= o.targets;
    if (withColors)
        for (int k = 0; k < 3; ++k) into.colors.back().rgb[k] += from.colors[j].rgb[k];
}

/// The partials of one block from several parts, as one: each part's leaves ascend, so they are
/// walked together, the voxels they share summed; the triangles in key order.
BlockPartial sumBlockPartials(const std::vector<const BlockPartial*>& partials, bool withColors) {
    BlockPartial sum;
    sum.coord = partials[0]->coord;
    std::vector<size_t> at(partials.size(), 0);
    for (;;) {
        uint32_t next = UINT32_MAX;
        for (size_t k = 0; k < partials.size(); ++k)
            if (at[k] < partials[k]->leafMorton.size()) next = std::min(next, partials[k]->leafMorton[at[k]]);
        if (next == UINT32_MAX) break;
        bool started = false;
        for (size_t k = 0; k < partials.size(); ++k) {
            const BlockPartial& q = *partials[k];
            if (at[k] >= q.leafMorton.size() || q.leafMorton[at[k]] != next) continue;
            if (!started) {
                sum.leafMorton.push_back(next);
                sum.leaves.push_back(q.leaves[at[k]]);
                if (withColors) sum.colors.push_back(q.colors[at[k]]);
                started = true;
            } else {
                addLeaf(sum, q, at[k], withColors);
            }
            ++at[k];
        }
    }
    std::vector<std::pair<uint64_t, const SourceTriangle*>> triangles;
    for (const BlockPartial* q : partials)
        for (size_t i = 0; i < q->triangles.size(); ++i) triangles.push_back({q->triangleKeys[i], &q->triangles[i]});
    std::sort(triangles.begin(), triangles.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [key, t] : triangles) sum.triangleKeys.push_back(key), sum.triangles.push_back(*t);
    return sum;
}

/// Finished blocks into the model, in order, leaving out those with nothing to draw; counted.
void keepFinishedBlocks(std::vector<VoxelBlock>& blocks, const std::vector<uint64_t>& touched, VoxelModel& model,
                        VoxelizeStats& stats) {
    for (size_t i = 0; i < blocks.size(); ++i) {
        stats.conservativeVoxels += touched[i];
        if (blocks[i].voxels.empty() && blocks[i].triangles.empty()) continue;
        stats.voxels += blocks[i].voxels.size();
        stats.sourceTriangles += blocks[i].triangles.size();
        model.blocks.push_back(std::move(blocks[i]));
    }
}

/// Gathers blocks straight from the per-thread trees, without merging them first (Chajdas merges
/// the trees, section 3.1.1; here the merge happens per block, in parallel): each tree's top levels
/// are walked once to list its block subtrees; subtrees of the same block are grouped (Morton order
/// of the block, then tree order); each block's leaves are then read on its own task in Morton
/// order, the leaves the trees share summed (a BlockPartial). Integer sums make the result the same
/// as a merged tree's, for any thread count — and for any split of the chunks among processes,
/// which is what lets partial voxelizations merge (mergePartialVoxelizations).
class BlockEmitter {
public:
    BlockEmitter(std::vector<const VoxelOctree*> trees, std::vector<BlockTriangleBuckets*> triangles)
        : trees_(std::move(trees)), triangles_(std::move(triangles)), leafDepth_(trees_[0]->leafDepth()),
          blockDepth_(std::max(0, leafDepth_ - log2OfPowerOfTwo(kBlockSize))), withColors_(trees_[0]->withColors()) {
        std::vector<SubtreeRef>& subtrees = subtrees_;
        for (uint32_t t = 0; t < trees_.size(); ++t) listBlocks(t, VoxelOctree::root(), 0, glm::uvec3(0), subtrees);
        std::sort(subtrees.begin(), subtrees.end(), [](const SubtreeRef& a, const SubtreeRef& b) {
            return a.morton != b.morton ? a.morton < b.morton : a.tree < b.tree;
        });
        for (size_t i = 0; i < subtrees.size();) {
            size_t j = i + 1;
            while (j < subtrees.size() && subtrees[j].morton == subtrees[i].morton) ++j;
            groups_.push_back({i, j});
            i = j;
        }
    }

    /// The whole model's blocks, in Morton order (each block's partial made and finished on one
    /// task, then dropped: the peak holds one partial per thread).
    void emit(const VoxelizeOptions& options, bool woundInwards, VoxelModel& model, VoxelizeStats& stats) {
        std::vector<VoxelBlock> blocks(groups_.size());
        std::vector<uint64_t> touched(groups_.size(), 0);  // conservative voxels per block
        raster::parallelFor(groups_.size(), [&](size_t g) {
            finishBlock(partialOf(g), options.separability, withColors_, model.blockSize, woundInwards, blocks[g], touched[g]);
        });
        keepFinishedBlocks(blocks, touched, model, stats);
    }

    /// Every block's partial, in Morton order.
    std::vector<BlockPartial> partials() {
        std::vector<BlockPartial> out(groups_.size());
        raster::parallelFor(groups_.size(), [&](size_t g) { out[g] = partialOf(g); });
        return out;
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

    BlockPartial partialOf(size_t g) const {
        const SubtreeRef* subtrees = &subtrees_[groups_[g].first];
        const size_t count = groups_[g].second - groups_[g].first;
        BlockPartial p;
        p.coord = subtrees[0].cell;
        std::vector<LeafRef> leaves;
        for (size_t s = 0; s < count; ++s) gather(subtrees[s].tree, subtrees[s].node, blockDepth_, glm::uvec3(0), leaves);
        // Each tree's leaves came in Morton order; with several trees, order them all (tree order
        // breaks ties) so shared leaves sit side by side.
        if (count > 1)
            std::sort(leaves.begin(), leaves.end(), [](const LeafRef& x, const LeafRef& y) {
                return x.localMorton != y.localMorton ? x.localMorton < y.localMorton : x.tree < y.tree;
            });
        for (size_t i = 0; i < leaves.size();) {
            p.leafMorton.push_back(leaves[i].localMorton);
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
            p.leaves.push_back(sums);
            if (withColors_) p.colors.push_back(colors);
            i = j;
        }
        gatherTriangles(subtrees[0].morton, p);
        return p;
    }

    /// Every thread's fan triangles for the block, in source triangle order (their keys kept, so
    /// partials of one block from other chunks merge into the same order). Each bucket is emptied
    /// as it is used (its own block's entry only, so blocks filled in parallel never touch the same
    /// entry, and the maps are not restructured), so the peak holds them once.
    void gatherTriangles(uint64_t morton, BlockPartial& p) const {
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
        p.triangleKeys.reserve(order.size());
        p.triangles.reserve(order.size());
        for (uint32_t i : order) p.triangleKeys.push_back(keys[i]), p.triangles.push_back(found[i]);
    }

    void gather(uint32_t t, uint32_t node, int depth, const glm::uvec3& local, std::vector<LeafRef>& out) const {
        if (depth == leafDepth_) {
            out.push_back({uint32_t(mortonOf(local)), t, node});
            return;
        }
        for (int octant = 0; octant < 8; ++octant)
            if (const uint32_t c = trees_[t]->existingChild(node, octant))
                gather(t, c, depth + 1, local * 2u + glm::uvec3(octant & 1, octant >> 1 & 1, octant >> 2 & 1), out);
    }

    std::vector<const VoxelOctree*> trees_;
    std::vector<BlockTriangleBuckets*> triangles_;
    int leafDepth_, blockDepth_;
    bool withColors_;
    std::vector<SubtreeRef> subtrees_;
    std::vector<std::pair<size_t, size_t>> groups_;  // [first, last) of each block's subtrees
};

}  // namespace

VoxelGrid gridFor(const MeshView& mesh, uint32_t resolution) {
    glm::vec3 lo, hi;
    mesh.bounds(lo, hi);
    if (lo.x > hi.x) lo = hi = glm::vec3(0.0f);
    return VoxelGrid::fitting(glm::dvec3(lo), glm::dvec3(hi), resolution);
}

namespace {

/// What voxelizeMesh and voxelizeChunks share: the model's header (grid, block size, separability,
/// colours) and the per-thread trees of chunks [first, first + count), with their statistics.
struct BuiltTrees {
    tbb::enumerable_thread_specific<std::unique_ptr<TreeBuilder>> builders;
    std::vector<TreeBuilder*> trees;
    WindingSums winding;  // the trees' sums, summed
};

VoxelModel modelHeader(const MeshView& mesh, const VoxelizeOptions& options) {
    if (!isValidResolution(options.resolution))
        throw std::invalid_argument("resolution " + std::to_string(options.resolution) +
                                    " is not a power of two from 2 to 65536");
    VoxelModel model;
    model.grid = options.grid ? *options.grid : gridFor(mesh, options.resolution);
    model.grid.resolution = options.resolution;
    model.blockSize = std::min(kBlockSize, options.resolution);
    model.separability = options.separability;
    model.hasColors = mesh.hasColors();
    return model;
}

void buildTrees(const MeshView& mesh, const VoxelizeOptions& options, const VoxelModel& model, size_t first, size_t count,
                BuiltTrees& built, VoxelizeStats& stats) {
    // Each chunk's first triangle's index in the whole mesh: the sort key that makes source
    // triangles come out in one order whatever thread (or process) read which chunk.
    std::vector<uint64_t> firstTriangle(mesh.chunkCount() + 1, 0);
    for (size_t i = 0; i < mesh.chunkCount(); ++i) firstTriangle[i + 1] = firstTriangle[i] + mesh.chunkInfo(i).triangleCount;
    stats.chunks = count;
    stats.triangles = firstTriangle[first + count] - firstTriangle[first];

    std::atomic<size_t> done{0};
    std::mutex progressMutex;
    double t0 = raster::nowMs();
    raster::parallelFor(count, [&](size_t i) {
        const size_t chunk = first + i;
        std::unique_ptr<TreeBuilder>& b = built.builders.local();
        if (!b) b = std::make_unique<TreeBuilder>(model.grid, options, model.hasColors);
        const double r0 = raster::nowMs();
        const GeometryChunk c = mesh.readChunk(chunk);
        b->readMs += raster::nowMs() - r0;
        b->insertChunk(c, firstTriangle[chunk]);
        const size_t n = ++done;
        if (options.progress) {
            std::lock_guard<std::mutex> lock(progressMutex);
            options.progress(n, count);
        }
    });
    stats.rasterizeMs = raster::nowMs() - t0;

    t0 = raster::nowMs();
    for (auto& b : built.builders)
        if (b) built.trees.push_back(b.get());
    stats.threads = int(built.trees.size());
    for (TreeBuilder* b : built.trees) {
        built.winding += b->winding();
        stats.octreeBytes += b->tree().reservedBytes();
        stats.leafPieces += b->leafPieces();
        stats.exactTests += b->exactTests();
        stats.readMs += b->readMs;
    }
    // The trees are merged block by block while emitting (BlockEmitter), not here.
    stats.mergeMs = raster::nowMs() - t0;
}

BlockEmitter emitterOf(const BuiltTrees& built) {
    std::vector<const VoxelOctree*> octrees;
    std::vector<BlockTriangleBuckets*> triangles;
    for (TreeBuilder* b : built.trees) octrees.push_back(&b->tree()), triangles.push_back(&b->blockTriangles());
    return BlockEmitter(std::move(octrees), std::move(triangles));
}

}  // namespace

VoxelModel voxelizeMesh(const MeshView& mesh, const VoxelizeOptions& options, VoxelizeStats* statsOut) {
    VoxelizeStats stats;
    VoxelModel model = modelHeader(mesh, options);
    BuiltTrees built;
    buildTrees(mesh, options, model, 0, mesh.chunkCount(), built, stats);
    const double t0 = raster::nowMs();
    stats.woundInwards = woundInwards(built.winding);
    if (!built.trees.empty()) emitterOf(built).emit(options, stats.woundInwards, model, stats);
    stats.blocks = model.blocks.size();
    stats.emitMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
    return model;
}

PartialVoxelization voxelizeChunks(const MeshView& mesh, const VoxelizeOptions& options, size_t firstChunk,
                                   size_t chunkCount, VoxelizeStats* statsOut) {
    if (firstChunk > mesh.chunkCount() || chunkCount > mesh.chunkCount() - firstChunk)
        throw std::invalid_argument("voxelizeChunks: chunks outside the mesh's " + std::to_string(mesh.chunkCount()));
    VoxelizeStats stats;
    PartialVoxelization part;
    part.header = modelHeader(mesh, options);
    part.firstChunk = firstChunk, part.chunkCount = chunkCount;
    BuiltTrees built;
    buildTrees(mesh, options, part.header, firstChunk, chunkCount, built, stats);
    const double t0 = raster::nowMs();
    if (!built.trees.empty()) part.blocks = emitterOf(built).partials();
    part.winding = built.winding;
    stats.emitMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
    return part;
}

VoxelModel mergePartialVoxelizations(std::vector<PartialVoxelization> parts, VoxelizeStats* statsOut) {
    if (parts.empty()) throw std::invalid_argument("mergePartialVoxelizations: no parts");
    // Parts in chunk order, each block's partials in part order: the order one process's trees give.
    std::sort(parts.begin(), parts.end(), [](const PartialVoxelization& a, const PartialVoxelization& b) {
        return a.firstChunk < b.firstChunk;
    });
    VoxelModel model = parts[0].header;
    const bool withColors = model.hasColors;
    struct Ref {
        uint64_t morton;
        uint32_t part, block;
    };
    std::vector<Ref> refs;
    for (uint32_t p = 0; p < parts.size(); ++p) {
        const VoxelModel& h = parts[p].header;
        if (h.grid.resolution != model.grid.resolution || h.grid.origin != model.grid.origin ||
            h.grid.extent != model.grid.extent || h.separability != model.separability || h.hasColors != withColors)
            throw std::invalid_argument("mergePartialVoxelizations: parts of different voxelizations");
        for (uint32_t b = 0; b < parts[p].blocks.size(); ++b) refs.push_back({mortonOf(parts[p].blocks[b].coord), p, b});
    }
    std::sort(refs.begin(), refs.end(), [](const Ref& a, const Ref& b) { return a.morton != b.morton ? a.morton < b.morton : a.part < b.part; });
    std::vector<std::pair<size_t, size_t>> groups;
    for (size_t i = 0; i < refs.size();) {
        size_t j = i + 1;
        while (j < refs.size() && refs[j].morton == refs[i].morton) ++j;
        groups.push_back({i, j});
        i = j;
    }
    WindingSums winding;
    for (const PartialVoxelization& p : parts) winding += p.winding;
    const bool inwards = woundInwards(winding);
    std::vector<VoxelBlock> blocks(groups.size());
    std::vector<uint64_t> touched(groups.size(), 0);
    raster::parallelFor(groups.size(), [&](size_t g) {
        std::vector<const BlockPartial*> partials;
        for (size_t k = groups[g].first; k < groups[g].second; ++k) partials.push_back(&parts[refs[k].part].blocks[refs[k].block]);
        if (partials.size() == 1)
            finishBlock(*partials[0], model.separability, withColors, model.blockSize, inwards, blocks[g], touched[g]);
        else
            finishBlock(sumBlockPartials(partials, withColors), model.separability, withColors, model.blockSize, inwards,
                        blocks[g], touched[g]);
    });
    VoxelizeStats stats;
    stats.woundInwards = inwards;
    for (const PartialVoxelization& p : parts) stats.chunks += p.chunkCount;
    keepFinishedBlocks(blocks, touched, model, stats);
    stats.blocks = model.blocks.size();
    if (statsOut) *statsOut = stats;
    return model;
}

}  // namespace cuberille::voxel
