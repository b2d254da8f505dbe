#pragma once
// Voxel simplification (Chajdas 2015, section 3.2): one level of the LOD pyramid from the level
// below, at half the resolution. Sort the voxels by parent position, then compact each run of
// children into one parent voxel:
//   - face mask: the union of the children's (a max on density, so a parent's faces bound its
//     children, which occlusion culling relies on: section 4.5);
//   - normal: the renormalised mean of the children's; colour: the mean, in linear space.
// Children are combined in Morton order, so the result does not depend on how the work was
// split. Two implementations that give identical output:
//   simplifySerial    streams parent blocks one at a time: the (at most 8) child blocks of one
//                     parent block and the parent itself are all it holds (section 3.2.1);
//   simplifyParallel  parallel sort of every voxel by its Morton key, run marking, prefix sum,
//                     compaction, one parent per run (section 3.2.2).

#include <functional>
#include <memory>
#include <vector>

#include "voxel/voxel_model.h"

namespace cuberille::lod {

/// The blocks of one level, in Morton order, read on demand: from memory, or from a .cvox file
/// one block at a time (so a level far larger than memory can be simplified).
class LevelSource {
public:
    virtual ~LevelSource() = default;
    virtual size_t blockCount() const = 0;
    virtual glm::uvec3 blockCoord(size_t block) const = 0;
    /// The block's voxels; released when the last pointer to it goes.
    virtual std::shared_ptr<const voxel::VoxelBlock> load(size_t block) const = 0;
};

/// The serial, streaming simplification: for each parent block in turn, load its (at most 8)
/// child blocks, build it, hand it to emit, release the children. At most 8 child blocks and one
/// parent are held at once, whatever the level's size.
void simplifySerial(const LevelSource& level, uint32_t blockSize, const std::function<void(voxel::VoxelBlock&&)>& emit);

/// `level`: the blocks of one level, in Morton order of their coordinates, each of size
/// blockSize with voxels in Morton order (as the voxelizer writes them). Returns the next level's
/// blocks, in the same orders, with level numbers one higher. Source triangles stay at level 0.
std::vector<voxel::VoxelBlock> simplifySerial(const std::vector<const voxel::VoxelBlock*>& level, uint32_t blockSize);
std::vector<voxel::VoxelBlock> simplifyParallel(const std::vector<const voxel::VoxelBlock*>& level, uint32_t blockSize);

}  // namespace cuberille::lod
