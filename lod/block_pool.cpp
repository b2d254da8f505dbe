#include "lod/block_pool.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace cuberille::lod {

BlockPool::BlockPool(uint64_t capacityBytes, double highWaterMark)
    : memory_(new std::byte[capacityBytes]),
      capacityBytes_(capacityBytes),
      highWaterBytes_(uint64_t(double(capacityBytes) * std::clamp(highWaterMark, 0.0, 1.0))) {}

std::optional<std::span<std::byte>> BlockPool::allocate(uint32_t block, uint64_t bytes) {
    if (entries_.count(block)) throw std::logic_error("BlockPool::allocate: block already in the pool");
    // Evict released blocks, oldest first, until the block fits beside everything kept.
    while (stats_.residentBytes + stats_.freeListBytes + bytes > capacityBytes() && !freeList_.empty()) evictOldest();
    if (stats_.residentBytes + stats_.freeListBytes + bytes > capacityBytes()) return std::nullopt;
    // Past the high-water mark (or the end), close the gaps first.
    const uint64_t used = stats_.residentBytes + stats_.freeListBytes;
    if (stats_.topBytes + bytes > highWaterBytes_ && stats_.topBytes > used) defragment();
    if (stats_.topBytes + bytes > capacityBytes()) defragment();
    Entry e;
    e.offset = stats_.topBytes;
    e.bytes = bytes;
    entries_[block] = e;
    stats_.topBytes += bytes;
    stats_.residentBytes += bytes;
    ++stats_.allocations;
    return std::span<std::byte>(memory_.get() + e.offset, bytes);
}

void BlockPool::release(uint32_t block) {
    auto it = entries_.find(block);
    if (it == entries_.end() || !it->second.resident) return;
    it->second.resident = false;
    it->second.releasedAt = ++releases_;
    freeList_[it->second.releasedAt] = block;
    stats_.residentBytes -= it->second.bytes;
    stats_.freeListBytes += it->second.bytes;
}

bool BlockPool::revive(uint32_t block) {
    auto it = entries_.find(block);
    if (it == entries_.end()) return false;
    if (it->second.resident) return true;
    freeList_.erase(it->second.releasedAt);
    it->second.resident = true;
    stats_.freeListBytes -= it->second.bytes;
    stats_.residentBytes += it->second.bytes;
    ++stats_.revivals;
    return true;
}

void BlockPool::discard(uint32_t block) {
    auto it = entries_.find(block);
    if (it == entries_.end()) return;
    if (it->second.resident) {
        stats_.residentBytes -= it->second.bytes;
    } else {
        freeList_.erase(it->second.releasedAt);
        stats_.freeListBytes -= it->second.bytes;
    }
    entries_.erase(it);
}

bool BlockPool::isResident(uint32_t block) const {
    const auto it = entries_.find(block);
    return it != entries_.end() && it->second.resident;
}

std::vector<uint32_t> BlockPool::residentBlocks() const {
    std::vector<uint32_t> out;
    for (const auto& [id, e] : entries_)
        if (e.resident) out.push_back(id);
    return out;
}

bool BlockPool::isOnFreeList(uint32_t block) const {
    const auto it = entries_.find(block);
    return it != entries_.end() && !it->second.resident;
}

std::span<std::byte> BlockPool::data(uint32_t block) {
    const Entry& e = entries_.at(block);
    return {memory_.get() + e.offset, e.bytes};
}

std::span<const std::byte> BlockPool::data(uint32_t block) const {
    const Entry& e = entries_.at(block);
    return {memory_.get() + e.offset, e.bytes};
}

void BlockPool::evictOldest() {
    const auto oldest = freeList_.begin();
    const Entry& e = entries_.at(oldest->second);
    stats_.freeListBytes -= e.bytes;
    entries_.erase(oldest->second);
    freeList_.erase(oldest);
    ++stats_.evictions;
}

void BlockPool::defragment() {
    // Kept blocks in address order, each moved down to the end of the one before.
    std::vector<Entry*> order;
    for (auto& [id, e] : entries_) order.push_back(&e);
    std::sort(order.begin(), order.end(), [](const Entry* a, const Entry* b) { return a->offset < b->offset; });
    uint64_t top = 0;
    for (Entry* e : order) {
        if (e->offset != top) {
            std::memmove(memory_.get() + top, memory_.get() + e->offset, e->bytes);
            stats_.bytesMoved += e->bytes;
            e->offset = top;
        }
        top += e->bytes;
    }
    stats_.topBytes = top;
    ++stats_.defragmentations;
}

}  // namespace cuberille::lod
