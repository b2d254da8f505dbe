#pragma once
// The adaptive octree voxelizer (Chajdas 2015, sections 3.1.1 and 3.1.2): every triangle walks
// down an octree over the grid's unit cube, split at each node's mid-planes into the pieces that
// fall in each child, until the pieces are single voxels. The tree adapts to the surface: only
// nodes a triangle touches are ever created.
//
//   voxelizeMesh
//     per chunk, on whichever thread is free (work stealing): read it, then insert each triangle
//       insertTriangle -> descend: split the piece at the node's mid-planes, recurse per child
//         at the block depth: keep the piece as a source triangle of that block
//         at the leaf depth: accumulate area-weighted normal and colour, active faces, targets
//     emit: list each tree's subtrees at the block depth, group them by block; per block, in
//           parallel, read their leaves in octant (Morton) order and sum the shared ones
//           (integer sums: the per-thread trees merge with the same bits in any order), keeping
//           the voxels the separability asks for

#include <cstdint>
#include <functional>
#include <optional>

#include "voxel/mesh_view.h"
#include "voxel/voxel_model.h"
#include "voxel/voxel_octree.h"

namespace cuberille::voxel {

struct VoxelizeOptions {
    uint32_t resolution = 256;  // a power of two, kMinResolution..kMaxResolution
    Separability separability = Separability::Conservative;
    /// The grid to voxelize into; by default the mesh's bounds (gridFor). A given grid lets
    /// several models share one, and tests place triangles exactly on voxel boundaries.
    /// Geometry outside it is clamped onto its faces.
    std::optional<VoxelGrid> grid;
    bool keepSourceTriangles = true;  // clip the source triangles per block (hybrid rendering)
    /// A face is active when the surface's unit normal n satisfies dot(n, face normal) > this
    /// (section 3.1.1): triangles lying in or parallel to a voxel face do not activate the side
    /// faces through rounding.
    double activeFaceEpsilon = 1e-3;
    /// Called from the calling thread's work as chunks finish (done, total); may be empty.
    std::function<void(size_t, size_t)> progress;
};

struct VoxelizeStats {
    uint64_t chunks = 0, triangles = 0;
    uint64_t leafPieces = 0;       // triangle pieces that reached a leaf (duplicates included)
    uint64_t exactTests = 0;       // leaf pieces near a voxel face, decided by the exact test
    uint64_t conservativeVoxels = 0;  // voxels the surface touches
    uint64_t voxels = 0;           // voxels kept by the separability
    uint64_t blocks = 0, sourceTriangles = 0;
    uint64_t octreeBytes = 0;      // all per-thread trees at their largest, before merging
    int threads = 0;               // trees built (threads that took at least one chunk)
    double readMs = 0;             // summed over threads: reading and decompressing chunks
    double rasterizeMs = 0;        // wall: reading and inserting every chunk
    double mergeMs = 0, emitMs = 0;  // merge: collecting the trees (they merge per block in emit)
    /// The mesh is wound clockwise seen from outside (its signed volume is negative): its voxels'
    /// normals and active faces were turned outwards (docs/voxelization.md).
    bool woundInwards = false;
};

/// Throws std::invalid_argument for a resolution that is not a power of two in range, and
/// scene::InputError for bad chunk data.
VoxelModel voxelizeMesh(const MeshView& mesh, const VoxelizeOptions& options, VoxelizeStats* stats = nullptr);

/// Which way a mesh is wound, as sums over its triangles (octree_voxelizer.cpp, woundInwards):
/// six times its signed volume seen from the grid's centre, and its triangles' area vectors
/// (the cross products of their edges), each term scaled and rounded to an integer and summed
/// with wrapping, so any split of the triangles sums to the same bits.
struct WindingSums {
    uint64_t volume = 0;
    uint64_t area[3] = {0, 0, 0};
    WindingSums& operator+=(const WindingSums& o) {
        volume += o.volume;
        for (int a = 0; a < 3; ++a) area[a] += o.area[a];
        return *this;
    }
};

/// One block's share of a voxelization from some of the mesh's chunks: the leaf sums of the voxels
/// those chunks' triangles touch (integer, before the separability's choice; ascending Morton code
/// within the block), and its source-triangle pieces with their order keys (source triangle index
/// << 8 | fan index, ascending). The partials of one block from any split of the chunks sum to the
/// whole mesh's leaf sums, and their keys interleave into its triangle order.
struct BlockPartial {
    glm::uvec3 coord{0};               // in blocks, at the finest level
    std::vector<uint32_t> leafMorton;  // each leaf's position in the block, as its Morton code
    std::vector<LeafSums> leaves;
    std::vector<LeafColorSums> colors;  // one per leaf, for a mesh with colours; else empty
    std::vector<uint64_t> triangleKeys;
    std::vector<SourceTriangle> triangles;
};

/// What voxelizing chunks [firstChunk, firstChunk + chunkCount) of a mesh gives: the model's header
/// (grid from the whole mesh's bounds, block size, separability, colours; no blocks) and the partial
/// blocks, in Morton order. A distributed voxelization's unit of work (python/cuberille/dask).
struct PartialVoxelization {
    VoxelModel header;
    uint64_t firstChunk = 0, chunkCount = 0;
    std::vector<BlockPartial> blocks;
    /// These chunks' share of the sums that say which way the mesh is wound: a mesh wound inwards
    /// has its normals and active faces turned outwards when the parts are merged, as voxelizeMesh
    /// does.
    WindingSums winding;
};
PartialVoxelization voxelizeChunks(const MeshView& mesh, const VoxelizeOptions& options, size_t firstChunk,
                                   size_t chunkCount, VoxelizeStats* stats = nullptr);

/// The partial voxelizations of every chunk of a mesh, merged: voxelizeMesh's model bit for bit,
/// whatever the split (VoxelizeChunks tests). Each block's partials are summed, the separability
/// applied and the triangles put in key order, exactly as voxelizeMesh finishes a block from its
/// threads' trees. Throws std::invalid_argument for parts of different voxelizations.
VoxelModel mergePartialVoxelizations(std::vector<PartialVoxelization> parts, VoxelizeStats* stats = nullptr);

/// The grid voxelizeMesh uses for a view: the view's bounds, uniformly scaled.
VoxelGrid gridFor(const MeshView& mesh, uint32_t resolution);

}  // namespace cuberille::voxel
