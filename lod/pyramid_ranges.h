#pragma once
// The LOD pyramid (lod/lod_pyramid.h) built a range of blocks at a time, so that no process of a
// distributed voxelization (python/cuberille/dask) holds the finest level whole, and written as
// the same .cvox bytes buildLodPyramid and writeCvox give for the whole model.
//
// Why ranges work: a parent block depends on its (at most 8) children alone (lod/simplify.h), and
// a level's blocks are in Morton order, so the level-0 blocks under one block of level S are the
// consecutive Morton codes [c * 8^S, (c + 1) * 8^S). A range is a run of such subtrees, and
// everything from level 0 up to level S inside it is built from the range alone:
//   per range (a worker): its level-0 blocks (merged from every part), levels 1..S built from them,
//     each of those blocks finished (hidden faces, skirts) and written to a range file, with a
//     copy of its level-S blocks as simplification left them (the level above is built from those);
//   joining (the client): the ranges' level-S copies read, levels S+1 and up built and finished,
//     every block linked from a layout of levels and coordinates, and the .cvox written in
//     writeCvox's order (coarsest level first, Morton within a level): the levels above S from
//     memory, the rest copied a block at a time from the range files.
// The joining process holds levels S and up: a 4^-S share of the finest level's voxels, give or
// take (a surface's voxel count quarters per level). planPyramidRanges picks S as high as the
// number of ranges wanted allows.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <ostream>
#include <utility>
#include <vector>

#include "lod/lod_pyramid.h"
#include "voxel/voxel_model.h"

namespace cuberille::voxel {
class PositionalFile;
}

namespace cuberille::lod {

struct PyramidRangePlan {
    uint32_t levels = 1;      // of the whole pyramid (PyramidOptions::maxLevels applied)
    uint32_t splitLevel = 0;  // S: ranges build levels 0..S, the join the levels above
    /// The level-0 Morton code where each range starts: ascending, the first 0, each a multiple of
    /// 8^S. Range k is [rangeStarts[k], rangeStarts[k + 1]), the last one open-ended.
    std::vector<uint64_t> rangeStarts{0};

    size_t rangeCount() const { return rangeStarts.size(); }
    uint64_t rangeBegin(size_t k) const { return rangeStarts[k]; }
    uint64_t rangeEnd(size_t k) const { return k + 1 < rangeStarts.size() ? rangeStarts[k + 1] : UINT64_MAX; }
};

/// Ranges for a model whose level-0 blocks are `blocks`: (Morton code, weight: bytes to merge),
/// in any order, a block named once per part that holds it. S is the highest level that still has
/// twice `wantedRanges` subtrees with blocks (fewer when level 0 has fewer blocks), and the
/// subtrees are cut into at most `wantedRanges` runs of about equal weight. Depends on its
/// arguments alone, so every process that plans from the same parts gets the same ranges.
PyramidRangePlan planPyramidRanges(std::vector<std::pair<uint64_t, uint64_t>> blocks, uint32_t levels,
                                   size_t wantedRanges);

/// One range: `range` holds the range's level-0 blocks (the merged voxelization restricted to it,
/// in Morton order). Builds levels 1..S, finishes every block, writes the range file. Returns the
/// faces cleared and skirted.
PyramidStats buildPyramidRange(voxel::VoxelModel range, const PyramidOptions& options, uint32_t splitLevel,
                               std::ostream& out);

/// The ranges' files joined: opened (tables read and checked), the levels above S built; then
/// write() gives the .cvox and, when asked, `--export-voxels`' text (voxel/voxel_export.h).
class PyramidRangeJoin {
public:
    /// `header`: the model's grid, block size, separability and colours (no blocks). Throws
    /// scene::InputError naming the file and field for a range file cut short or of another model.
    PyramidRangeJoin(const voxel::VoxelModel& header, const std::vector<std::filesystem::path>& rangeFiles,
                     const PyramidOptions& options, const PyramidRangePlan& plan);
    ~PyramidRangeJoin();

    /// Every block's level, coordinates, counts, bounds and links; the voxels of the levels above S.
    const voxel::VoxelModel& layout() const { return layout_; }
    /// As buildLodPyramid reports them (simplifyMs: the join's own building).
    const PyramidStats& stats() const { return stats_; }

    void write(std::ostream& cvox, std::ostream* exportVoxels) const;

private:
    struct Stored {
        uint32_t file = 0;
        uint64_t offset = 0;
    };
    std::vector<std::unique_ptr<voxel::PositionalFile>> files_;
    voxel::VoxelModel layout_;
    size_t loadedBlocks_ = 0;     // layout_.blocks[0, loadedBlocks_) hold their voxels
    std::vector<Stored> stored_;  // where each later block's data lies
    PyramidStats stats_;
};

}  // namespace cuberille::lod
