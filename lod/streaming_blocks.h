#pragma once
// A .cvox model streamed under a memory budget (Chajdas 2015, sections 4.4 and 4.6). The root
// block is read when the model opens and stays resident, so the first frame needs nothing else
// (a closed, coarse model at once, whatever the model's size). Every other block is read on the
// I/O thread when a frame asks for it; once per frame (beginFrame) what it has read is made
// resident, up to the upload limit, the rest waiting in staging for later frames so frame times
// stay even. Blocks a frame did not use go to their pool's free list, still intact, and are
// revived without touching the disk if a later frame wants them back.
//
// Three pools, as in the paper: voxels (the three 32-bit arrays, 12 bytes a voxel), triangle
// vertices (positions, normals and linear colours, 36 bytes a vertex) and triangle indices
// (12 bytes a triangle). The budget is split among them: half for voxels and a quarter for
// each triangle pool when the model has source triangles, all for voxels when it has none.
//
// Faults: a block that cannot be read is reported once (through the warning callback), marked
// failed, and never requested again; the renderer draws its nearest resident ancestor there.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "lod/block_loader.h"
#include "lod/block_pool.h"
#include "lod/block_source.h"
#include "voxel/cvox_file.h"

namespace cuberille::lod {

struct StreamingOptions {
    uint64_t budgetBytes = 1024ull << 20;  // --budget-mib
    uint64_t uploadLimitBytes = 0;         // --upload-limit (per frame); 0: unlimited
    double ioThrottleMibPerSecond = 0.0;   // --io-throttle: a slow disk; 0: as fast as the disk
    double highWaterMark = 0.95;           // defragment past this share of a pool
};

enum PoolKind { kVoxelPool = 0, kVertexPool = 1, kIndexPool = 2, kPoolCount = 3 };
const char* poolName(PoolKind pool);

/// One frame's streaming, for `fly --stats` (byte counts are this frame's unless said otherwise).
struct StreamingFrameStats {
    uint64_t requestedBytes = 0;   // what this frame asked the I/O thread for (file bytes)
    uint64_t loadedBytes = 0;      // read from disk since the last frame (file bytes)
    uint64_t uploadedBytes = 0;    // made resident from staging (pool bytes)
    uint64_t revivedBytes = 0;     // made resident again from a free list
    uint64_t stagedBytes = 0;      // read but waiting for the upload limit (file bytes, at the end)
    uint64_t droppedBytes = 0;     // read, but no room under the budget
    uint64_t residentBytes[kPoolCount] = {};  // at the end of the frame
    uint64_t freeListBytes[kPoolCount] = {};
    uint64_t defragmentations = 0;  // this frame, all pools
    uint64_t failedBlocks = 0;      // newly failed this frame
    uint32_t requests = 0;          // blocks asked for
    double uploadMs = 0.0;          // taking in and copying into the pools
};

class StreamingBlocks final : public BlockSource {
public:
    /// Reads the root block (throws scene::InputError when even that cannot be read).
    /// warn receives each failed block's message, once.
    StreamingBlocks(const voxel::CvoxReader& reader, const StreamingOptions& options,
                    std::function<void(const std::string&)> warn);
    ~StreamingBlocks() override;

    const voxel::VoxelModel& layout() const override { return reader_.layout(); }
    void beginFrame() override;
    bool acquire(uint32_t block, BlockParts part) override;
    voxel::BlockVoxels voxels(uint32_t block) const override;
    TriangleView triangles(uint32_t block) const override;
    bool failed(uint32_t block) const override { return failed_.count(block) != 0; }
    void endFrame(std::vector<BlockRequest> missing) override;

    /// Nothing queued, being read or staged, and the last frame missed nothing: the image will not
    /// change any more for this camera.
    bool settled() const;
    /// Waits until the I/O thread has read something or has nothing left; milliseconds waited.
    double waitForLoads() const;
    /// The last completed frame's streaming.
    const StreamingFrameStats& frameStats() const { return frame_; }
    const BlockPool& pool(PoolKind kind) const { return *pools_[kind]; }
    uint64_t capacityBytes() const;
    /// Defragmentations so far, all pools.
    uint64_t defragmentations() const;
    uint64_t bytesReadFromDisk() const { return loader_->bytesRead() + rootBytes_; }

private:
    /// Copies a loaded block's parts into the pools; false when the budget has no room.
    bool makeResident(const LoadedBlock& loaded);
    bool isResident(uint32_t block, BlockParts part) const;
    bool revive(uint32_t block, BlockParts part);
    void releaseUnused();
    std::vector<BlockRequest> withinBudget(std::vector<BlockRequest> missing) const;
    /// Vertex-pool bytes a block's triangles take: exact once indexed, else estimated from the
    /// vertices per triangle seen so far (the count is known only after merging).
    uint64_t vertexBytes(uint32_t block) const;
    void noteFailure(uint32_t block, const std::string& error);

    const voxel::CvoxReader& reader_;
    StreamingOptions options_;
    std::function<void(const std::string&)> warn_;
    std::unique_ptr<BlockPool> pools_[kPoolCount];
    std::vector<LoadedBlock> staging_;  // read, waiting for the upload limit
    std::set<uint32_t> failed_;
    // This frame's acquisitions: block -> the parts used (kept resident; the rest are released).
    std::map<uint32_t, uint8_t> used_;
    std::vector<BlockRequest> lastRequests_;
    std::map<uint32_t, uint32_t> vertexCounts_;  // blocks whose triangles were indexed: their vertices
    uint64_t verticesSeen_ = 0, trianglesSeen_ = 0;
    StreamingFrameStats frame_, current_;
    uint64_t rootBytes_ = 0;
    std::unique_ptr<BlockLoader> loader_;  // last: its thread stops before the rest goes
};

}  // namespace cuberille::lod
