#pragma once
// Where a frame's block data comes from (Chajdas 2015, sections 4.4 and 4.6). The renderer
// (lod/voxel_scene.h) selects blocks from the layout alone — level, coordinates, tight bounds,
// links and counts are in the block table — and then asks the source for each selected block's
// data. A model in memory has every block resident; a streamed model (lod/streaming_blocks.h)
// has only what its pools hold, and is told at the end of the frame what was missing.
//
// Resident data is in the form the rasterizer draws, so a frame reads it in place: a block's
// voxels as its three 32-bit arrays (expanded to faces every frame, section 4.3), its source
// triangles as unique vertices (positions, normals, linear colours) and an index list, the
// vertex and index caches of section 4.7.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "voxel/cvox_file.h"
#include "voxel/face_expansion.h"
#include "voxel/voxel_model.h"

namespace cuberille::lod {

using BlockParts = voxel::CvoxReader::Parts;

/// A block's source triangles, ready to draw.
struct TriangleView {
    std::span<const glm::vec3> positions, normals, colors;
    std::span<const uint32_t> indices;
};

struct IndexedTriangles {
    std::vector<glm::vec3> positions, normals, colors;
    std::vector<uint32_t> indices;

    TriangleView view() const { return {positions, normals, colors, indices}; }
};

/// The block's triangles with identical vertices (position, normal and colour bits) merged: the
/// clipped fans and shared corners of a block repeat most vertices. Deterministic: vertices in
/// order of first use.
IndexedTriangles indexSourceTriangles(std::span<const voxel::SourceTriangle> triangles);

/// A block (and the parts of it) a frame needed and did not find resident.
struct BlockRequest {
    uint32_t block = 0;
    BlockParts parts = BlockParts::kVoxels;
    BlockRequest(uint32_t b = 0, BlockParts p = BlockParts::kAllParts) : block(b), parts(p) {}
};

class BlockSource {
public:
    virtual ~BlockSource() = default;

    /// Every block's metadata and counts; its data may or may not be loaded.
    virtual const voxel::VoxelModel& layout() const = 0;

    /// Once per frame, before any acquire (streaming: takes in what the I/O thread read).
    virtual void beginFrame() {}
    /// The frame uses this part of the block: true when it is resident now (a streamed block on
    /// the free list is revived). Views stay valid until the next beginFrame.
    virtual bool acquire(uint32_t block, BlockParts part) = 0;
    virtual voxel::BlockVoxels voxels(uint32_t block) const = 0;  // acquired kVoxels only
    virtual TriangleView triangles(uint32_t block) const = 0;     // acquired kTriangles only
    /// True when the block cannot be read; its nearest resident ancestor stands in for it.
    virtual bool failed(uint32_t /*block*/) const { return false; }
    /// After the frame's draws: what it missed, most important first. Blocks not acquired this
    /// frame may be released.
    virtual void endFrame(std::vector<BlockRequest> /*missing*/) {}
};

/// A whole model in memory: every block resident, nothing ever missing.
class ModelBlocks final : public BlockSource {
public:
    explicit ModelBlocks(voxel::VoxelModel model);

    const voxel::VoxelModel& layout() const override { return model_; }
    /// A block's source triangles are indexed the first time a frame draws them, and kept in that
    /// form (the model keeps their count): a run whose frames never come close enough to draw
    /// source triangles never pays for them (the dragon at 2048^3: about 0.3 s of CPU time for
    /// all 2,398 blocks, on every load).
    bool acquire(uint32_t block, BlockParts part) override;
    voxel::BlockVoxels voxels(uint32_t block) const override {
        return voxel::BlockVoxels::of(model_.blocks[block]);
    }
    TriangleView triangles(uint32_t block) const override { return triangles_[block].view(); }

private:
    voxel::VoxelModel model_;
    std::vector<IndexedTriangles> triangles_;
};

}  // namespace cuberille::lod
