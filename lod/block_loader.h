#pragma once
// The I/O thread of streaming (Chajdas 2015, section 4.6): blocks are read from the .cvox on a
// dedicated thread, so a frame never waits on the disk. Once per frame the renderer hands over
// its requests, most important first, replacing whatever was still queued (requests a frame no
// longer makes are dropped before they cost a read), and takes in what has been read since.
// A block that cannot be read (truncated, corrupt, I/O error) comes back with its error instead
// of its data; the thread goes on with the next request.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "lod/block_source.h"
#include "voxel/cvox_file.h"

namespace cuberille::lod {

struct LoadedBlock {
    uint32_t block = 0;
    BlockParts parts = BlockParts::kAllParts;
    std::optional<voxel::VoxelBlock> data;  // empty when the read failed
    std::string error;                      // why, naming the file and place
    uint64_t bytes = 0;                     // read from the file
};

class BlockLoader {
public:
    /// throttleMibPerSecond > 0 simulates a slow disk (--io-throttle).
    explicit BlockLoader(const voxel::CvoxReader& reader, double throttleMibPerSecond = 0.0);
    ~BlockLoader();
    BlockLoader(const BlockLoader&) = delete;
    BlockLoader& operator=(const BlockLoader&) = delete;

    /// This frame's requests, most important first; queued requests not among them are dropped.
    void replaceRequests(std::vector<BlockRequest> requests);
    /// Everything read since the last call, in the order it was read.
    std::vector<LoadedBlock> takeCompleted();
    /// True when nothing is queued, being read, or read and not yet taken.
    bool idle() const;
    /// Waits until something has been read and not yet taken, or nothing is left to read.
    void waitForCompleted() const;
    uint64_t bytesRead() const;

private:
    void run();

    const voxel::CvoxReader& reader_;
    double throttleBytesPerSecond_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    mutable std::condition_variable done_;
    std::deque<BlockRequest> queue_;
    std::vector<LoadedBlock> completed_;
    bool reading_ = false, stop_ = false;
    uint64_t bytesRead_ = 0;
    std::thread thread_;  // last: started once everything above exists
};

}  // namespace cuberille::lod
