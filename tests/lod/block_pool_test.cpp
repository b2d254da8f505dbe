// The resident-block pool: within its budget always, every kept block's bytes intact through
// evictions and defragmentations, released blocks revived as they were, oldest evicted first.

#include <map>
#include <random>

#include <gtest/gtest.h>

#include "lod/block_pool.h"

namespace cuberille {
namespace {

std::byte patternByte(uint32_t block, uint64_t i) {
    uint64_t x = (uint64_t(block) << 32) ^ (i * 0x9E3779B97F4A7C15ull);
    x ^= x >> 29;
    return std::byte(uint8_t(x * 0xBF58476D1CE4E5B9ull >> 56));
}

void fill(std::span<std::byte> bytes, uint32_t block) {
    for (uint64_t i = 0; i < bytes.size(); ++i) bytes[i] = patternByte(block, i);
}

bool intact(std::span<const std::byte> bytes, uint32_t block) {
    for (uint64_t i = 0; i < bytes.size(); ++i)
        if (bytes[i] != patternByte(block, i)) return false;
    return true;
}

TEST(BlockPool, StaysWithinBudgetAndKeepsEveryBlockIntactThroughDefragmentation) {
    const uint64_t capacity = 64 * 1024;
    lod::BlockPool pool(capacity);
    std::mt19937 rng(17);
    std::map<uint32_t, uint64_t> sizes;  // every block ever allocated
    uint32_t next = 1;
    for (int op = 0; op < 20000; ++op) {
        const int kind = int(rng() % 10);
        if (kind < 5) {  // a new block
            const uint64_t bytes = 1 + rng() % 6000;
            const uint64_t residentBefore = pool.stats().residentBytes;
            const auto span = pool.allocate(next, bytes);
            if (span) {
                fill(*span, next);
                sizes[next] = bytes;
            } else {
                EXPECT_GT(residentBefore + bytes, capacity) << "refused although it fits beside the resident blocks";
            }
            ++next;
        } else if (kind < 8 && !sizes.empty()) {  // release or revive some block
            auto it = sizes.lower_bound(uint32_t(1 + rng() % next));
            if (it == sizes.end()) continue;
            if (pool.isResident(it->first)) pool.release(it->first);
            else if (!pool.revive(it->first)) sizes.erase(it);  // evicted: gone
        } else if (!sizes.empty()) {  // drop one entirely
            auto it = sizes.lower_bound(uint32_t(1 + rng() % next));
            if (it == sizes.end()) continue;
            pool.discard(it->first);
            sizes.erase(it);
        }
        const lod::BlockPoolStats& s = pool.stats();
        ASSERT_LE(s.topBytes, capacity);
        ASSERT_LE(s.residentBytes + s.freeListBytes, s.topBytes);
        if (op % 97 == 0)  // every kept block, resident or released, byte for byte
            for (const auto& [block, bytes] : sizes)
                if (pool.isResident(block) || pool.isOnFreeList(block)) {
                    ASSERT_EQ(pool.data(block).size(), bytes);
                    ASSERT_TRUE(intact(pool.data(block), block)) << "block " << block << " after op " << op;
                }
    }
    EXPECT_GT(pool.stats().defragmentations, 10u);
    EXPECT_GT(pool.stats().evictions, 10u);
    EXPECT_GT(pool.stats().revivals, 10u);
}

TEST(BlockPool, RevivesReleasedBlocksAndEvictsTheOldestReleaseFirst) {
    lod::BlockPool pool(1000);
    for (uint32_t b = 1; b <= 4; ++b) fill(*pool.allocate(b, 250), b);
    pool.release(2);
    pool.release(1);  // 2 is the oldest release
    ASSERT_TRUE(pool.allocate(5, 250).has_value());  // needs one block's room: evicts 2
    EXPECT_FALSE(pool.isOnFreeList(2));
    EXPECT_TRUE(pool.isOnFreeList(1));
    EXPECT_TRUE(pool.revive(1));
    EXPECT_TRUE(intact(pool.data(1), 1));
    EXPECT_FALSE(pool.revive(2));
    EXPECT_FALSE(pool.allocate(6, 1).has_value()) << "full of resident blocks";
}

}  // namespace
}  // namespace cuberille
