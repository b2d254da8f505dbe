#pragma once
// A pool of resident block data under a fixed budget (Chajdas 2015, section 4.4): a linear
// allocator with a high-water mark. Blocks are placed at the top; a released block goes onto a
// free list with its bytes intact, so a later request for it is revived without touching the
// disk. When the top would pass the end, free-list blocks are evicted, oldest release first; when
// it would pass the high-water mark (95% by default) and there are gaps, the pool is
// defragmented: every kept block is moved down, in address order, into the gaps. Moves use
// memmove, which is the scratch copy the paper needs where source and target overlap. Cost is
// linear in the blocks kept.
//
// Deterministic: decisions depend only on the sequence of calls (ids in ordered maps, eviction by
// a release counter), never on addresses or hash order.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace cuberille::lod {

struct BlockPoolStats {
    uint64_t residentBytes = 0, freeListBytes = 0, topBytes = 0;
    uint64_t allocations = 0, revivals = 0, evictions = 0, defragmentations = 0, bytesMoved = 0;
};

class BlockPool {
public:
    explicit BlockPool(uint64_t capacityBytes, double highWaterMark = 0.95);

    uint64_t capacityBytes() const { return capacityBytes_; }
    /// What an allocation may take: everything not resident (free-list blocks give way).
    uint64_t roomBytes() const { return capacityBytes_ - stats_.residentBytes; }

    /// Space for a block not in the pool: its bytes (to be filled by the caller), or nullopt when
    /// even after evicting every free-list block and defragmenting it cannot fit beside the
    /// resident blocks. Offsets of other blocks may change (defragmentation): ask data() again.
    std::optional<std::span<std::byte>> allocate(uint32_t block, uint64_t bytes);
    /// The block leaves the resident set; its bytes stay until evicted.
    void release(uint32_t block);
    /// A released block back to resident, its bytes as they were; false when it was evicted (or
    /// never here).
    bool revive(uint32_t block);
    /// Drops a block entirely (resident or released), e.g. after a failed read.
    void discard(uint32_t block);

    bool isResident(uint32_t block) const;
    /// The resident blocks, in id order.
    std::vector<uint32_t> residentBlocks() const;
    bool isOnFreeList(uint32_t block) const;
    std::span<std::byte> data(uint32_t block);
    std::span<const std::byte> data(uint32_t block) const;

    const BlockPoolStats& stats() const { return stats_; }

private:
    struct Entry {
        uint64_t offset = 0, bytes = 0;
        bool resident = true;
        uint64_t releasedAt = 0;  // release counter, for oldest-first eviction
    };

    void evictOldest();
    void defragment();

    std::unique_ptr<std::byte[]> memory_;  // not zeroed: pages are touched only as blocks arrive
    uint64_t capacityBytes_;
    uint64_t highWaterBytes_;
    std::map<uint32_t, Entry> entries_;
    std::map<uint64_t, uint32_t> freeList_;  // release counter -> block: the oldest first
    uint64_t releases_ = 0;
    BlockPoolStats stats_;
};

}  // namespace cuberille::lod
