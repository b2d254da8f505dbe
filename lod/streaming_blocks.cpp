#include "lod/streaming_blocks.h"

#include <algorithm>
#include <cstring>

#include "raster/clock.h"
#include "scene/input_error.h"

namespace cuberille::lod {
namespace {

constexpr uint64_t kVoxelBytes = 12;              // packed position and faces, normal, colour
constexpr uint64_t kVertexBytes = 3 * 12;         // position, normal, linear colour
constexpr uint64_t kTriangleIndexBytes = 3 * 4;  // three 32-bit indices

template <typename T>
void copyInto(std::byte*& at, const std::vector<T>& values) {
    std::memcpy(at, values.data(), values.size() * sizeof(T));
    at += values.size() * sizeof(T);
}

template <typename T>
std::span<const T> viewAt(std::span<const std::byte> bytes, size_t first, size_t count) {
    return {reinterpret_cast<const T*>(bytes.data()) + first, count};
}

}  // namespace

const char* poolName(PoolKind pool) {
    switch (pool) {
        case kVoxelPool: return "voxels";
        case kVertexPool: return "vertices";
        case kIndexPool: return "indices";
        default: return "?";
    }
}

StreamingBlocks::StreamingBlocks(const voxel::CvoxReader& reader, const StreamingOptions& options,
                                 std::function<void(const std::string&)> warn)
    : reader_(reader), options_(options), warn_(std::move(warn)) {
    const bool hasTriangles = reader.layout().triangleCount() > 0;
    const uint64_t voxelShare = hasTriangles ? options.budgetBytes / 2 : options.budgetBytes;
    const uint64_t triangleShare = hasTriangles ? (options.budgetBytes - voxelShare) / 2 : 0;
    pools_[kVoxelPool] = std::make_unique<BlockPool>(voxelShare, options.highWaterMark);
    pools_[kVertexPool] = std::make_unique<BlockPool>(triangleShare, options.highWaterMark);
    pools_[kIndexPool] = std::make_unique<BlockPool>(options.budgetBytes - voxelShare - triangleShare, options.highWaterMark);
    if (reader.blockCount() > 0) {
        // The root, read now and kept: every frame can fall back to it.
        LoadedBlock root;
        root.block = 0;
        root.parts = BlockParts::kAllParts;
        root.data = reader.load(0, root.parts);
        rootBytes_ = reader.partBytes(0, root.parts);
        if (!makeResident(root))
            throw scene::InputError("the memory budget (" + std::to_string(options.budgetBytes >> 20) +
                                    " MiB) cannot hold the model's root block");
    }
    loader_ = std::make_unique<BlockLoader>(reader, options.ioThrottleMibPerSecond);
}

StreamingBlocks::~StreamingBlocks() = default;

uint64_t StreamingBlocks::defragmentations() const {
    uint64_t n = 0;
    for (const auto& p : pools_) n += p->stats().defragmentations;
    return n;
}

uint64_t StreamingBlocks::capacityBytes() const {
    uint64_t total = 0;
    for (const auto& p : pools_) total += p->capacityBytes();
    return total;
}

void StreamingBlocks::beginFrame() {
    current_ = {};
    const double t0 = raster::nowMs();
    for (LoadedBlock& loaded : loader_->takeCompleted()) {
        current_.loadedBytes += loaded.bytes;
        if (!loaded.data) noteFailure(loaded.block, loaded.error);
        else staging_.push_back(std::move(loaded));
    }
    // Upload in the order read (most important first within each frame's requests), up to the
    // limit; a block larger than the limit still goes when it is the frame's first, so nothing
    // waits forever.
    size_t taken = 0;
    for (; taken < staging_.size(); ++taken) {
        const LoadedBlock& b = staging_[taken];
        const uint64_t bytes = b.data->voxels.size() * kVoxelBytes + b.data->triangles.size() * 3 * kVertexBytes;
        if (options_.uploadLimitBytes && current_.uploadedBytes > 0 &&
            current_.uploadedBytes + bytes > options_.uploadLimitBytes)
            break;
        if (isResident(b.block, b.parts)) continue;  // revived meanwhile
        if (!makeResident(b)) current_.droppedBytes += b.bytes;
    }
    staging_.erase(staging_.begin(), staging_.begin() + std::ptrdiff_t(taken));
    current_.uploadMs = raster::nowMs() - t0;
}

bool StreamingBlocks::makeResident(const LoadedBlock& loaded) {
    const voxel::VoxelBlock& b = *loaded.data;
    const uint32_t id = loaded.block;
    const uint64_t before = defragmentations();
    bool ok = true;
    if ((loaded.parts & BlockParts::kVoxels) && !b.voxels.empty() && !pools_[kVoxelPool]->isResident(id)) {
        pools_[kVoxelPool]->discard(id);  // a stale copy on the free list
        const auto space = pools_[kVoxelPool]->allocate(id, b.voxels.size() * kVoxelBytes);
        if (space) {
            std::byte* at = space->data();
            copyInto(at, b.voxels), copyInto(at, b.normals), copyInto(at, b.colors);
            current_.uploadedBytes += space->size();
        } else {
            ok = false;
        }
    }
    if ((loaded.parts & BlockParts::kTriangles) && !b.triangles.empty() && !isResident(id, BlockParts::kTriangles)) {
        // Refused before the (costly) merge when it could not fit: indices are known exactly, and
        // vertices once the block has been merged before.
        const uint64_t indexBytes = b.triangles.size() * kTriangleIndexBytes;
        const auto known = vertexCounts_.find(id);
        if (indexBytes > pools_[kIndexPool]->roomBytes() ||
            (known != vertexCounts_.end() && known->second * kVertexBytes > pools_[kVertexPool]->roomBytes())) {
            ok = false;
        } else {
            const IndexedTriangles t = indexSourceTriangles(b.triangles);
            if (known == vertexCounts_.end()) {
                vertexCounts_[id] = uint32_t(t.positions.size());
                verticesSeen_ += t.positions.size();
                trianglesSeen_ += b.triangles.size();
            }
            pools_[kVertexPool]->discard(id);
            pools_[kIndexPool]->discard(id);
            const auto vertices = pools_[kVertexPool]->allocate(id, t.positions.size() * kVertexBytes);
            const auto indices = vertices ? pools_[kIndexPool]->allocate(id, t.indices.size() * 4) : std::nullopt;
            if (vertices && indices) {
                std::byte* at = vertices->data();
                copyInto(at, t.positions), copyInto(at, t.normals), copyInto(at, t.colors);
                at = indices->data();
                copyInto(at, t.indices);
                current_.uploadedBytes += vertices->size() + indices->size();
            } else {
                pools_[kVertexPool]->discard(id);
                ok = false;
            }
        }
    }
    current_.defragmentations += defragmentations() - before;
    return ok;
}

bool StreamingBlocks::isResident(uint32_t block, BlockParts part) const {
    const voxel::VoxelBlock& b = layout().blocks[block];
    const bool voxels = !(part & BlockParts::kVoxels) || !b.hasVoxels() || pools_[kVoxelPool]->isResident(block);
    const bool triangles = !(part & BlockParts::kTriangles) || !b.hasTriangles() ||
                           (pools_[kVertexPool]->isResident(block) && pools_[kIndexPool]->isResident(block));
    return voxels && triangles;
}

bool StreamingBlocks::revive(uint32_t block, BlockParts part) {
    auto reviveIn = [&](PoolKind k) {
        BlockPool& p = *pools_[k];
        if (p.isResident(block)) return true;
        if (!p.isOnFreeList(block)) return false;
        p.revive(block);
        current_.revivedBytes += p.data(block).size();
        return true;
    };
    if (part == BlockParts::kVoxels) return reviveIn(kVoxelPool);
    // A triangle block lives in two pools: revived only when both still hold it.
    if (!pools_[kVertexPool]->isResident(block) && !pools_[kVertexPool]->isOnFreeList(block)) return false;
    if (!pools_[kIndexPool]->isResident(block) && !pools_[kIndexPool]->isOnFreeList(block)) return false;
    return reviveIn(kVertexPool) && reviveIn(kIndexPool);
}

bool StreamingBlocks::acquire(uint32_t block, BlockParts part) {
    used_[block] |= part;
    if (failed(block)) return false;
    if (isResident(block, part)) return true;
    if (part & BlockParts::kVoxels && !isResident(block, BlockParts::kVoxels) && !revive(block, BlockParts::kVoxels))
        return false;
    if (part & BlockParts::kTriangles && !isResident(block, BlockParts::kTriangles) &&
        !revive(block, BlockParts::kTriangles))
        return false;
    return true;
}

voxel::BlockVoxels StreamingBlocks::voxels(uint32_t block) const {
    const voxel::VoxelBlock& b = layout().blocks[block];
    voxel::BlockVoxels v{b.level, b.coord, {}, {}, {}};
    if (!pools_[kVoxelPool]->isResident(block)) return v;
    const auto bytes = pools_[kVoxelPool]->data(block);
    const size_t n = bytes.size() / kVoxelBytes;
    v.voxels = viewAt<uint32_t>(bytes, 0, n);
    v.normals = viewAt<uint32_t>(bytes, n, n);
    v.colors = viewAt<uint32_t>(bytes, 2 * n, n);
    return v;
}

TriangleView StreamingBlocks::triangles(uint32_t block) const {
    TriangleView t;
    if (!pools_[kVertexPool]->isResident(block) || !pools_[kIndexPool]->isResident(block)) return t;
    const auto vertices = pools_[kVertexPool]->data(block);
    const size_t n = vertices.size() / kVertexBytes;
    t.positions = viewAt<glm::vec3>(vertices, 0, n);
    t.normals = viewAt<glm::vec3>(vertices, n, n);
    t.colors = viewAt<glm::vec3>(vertices, 2 * n, n);
    const auto indices = pools_[kIndexPool]->data(block);
    t.indices = viewAt<uint32_t>(indices, 0, indices.size() / 4);
    return t;
}

void StreamingBlocks::endFrame(std::vector<BlockRequest> missing) {
    releaseUnused();
    used_.clear();
    // Not again what failed or what already waits in staging.
    std::erase_if(missing, [&](const BlockRequest& r) {
        if (failed(r.block)) return true;
        return std::any_of(staging_.begin(), staging_.end(),
                           [&](const LoadedBlock& s) { return s.block == r.block && (s.parts & r.parts) == r.parts; });
    });
    missing = withinBudget(std::move(missing));
    for (const BlockRequest& r : missing) current_.requestedBytes += reader_.partBytes(r.block, r.parts);
    current_.requests = uint32_t(missing.size());
    lastRequests_ = missing;
    loader_->replaceRequests(std::move(missing));
    for (int k = 0; k < kPoolCount; ++k) {
        current_.residentBytes[k] = pools_[k]->stats().residentBytes;
        current_.freeListBytes[k] = pools_[k]->stats().freeListBytes;
    }
    for (const LoadedBlock& s : staging_) current_.stagedBytes += s.bytes;
    frame_ = current_;
}

void StreamingBlocks::releaseUnused() {
    auto usedPart = [&](uint32_t block, BlockParts part) {
        if (block == 0) return true;  // the root stays
        const auto it = used_.find(block);
        return it != used_.end() && (it->second & part);
    };
    for (uint32_t b : pools_[kVoxelPool]->residentBlocks())
        if (!usedPart(b, BlockParts::kVoxels)) pools_[kVoxelPool]->release(b);
    for (PoolKind k : {kVertexPool, kIndexPool})
        for (uint32_t b : pools_[k]->residentBlocks())
            if (!usedPart(b, BlockParts::kTriangles)) pools_[k]->release(b);
}

std::vector<BlockRequest> StreamingBlocks::withinBudget(std::vector<BlockRequest> missing) const {
    // Ask only for what could be made resident beside this frame's blocks (the free lists give
    // way): a read that could never be uploaded would be read, dropped and asked for again.
    uint64_t room[kPoolCount];
    for (int k = 0; k < kPoolCount; ++k) room[k] = pools_[k]->roomBytes();
    std::vector<BlockRequest> kept;
    for (const BlockRequest& r : missing) {
        const voxel::VoxelBlock& b = layout().blocks[r.block];
        uint64_t need[kPoolCount] = {};
        if (r.parts & BlockParts::kVoxels) need[kVoxelPool] = b.totalVoxels() * kVoxelBytes;
        if (r.parts & BlockParts::kTriangles) {
            need[kVertexPool] = vertexBytes(r.block);
            need[kIndexPool] = b.totalTriangles() * kTriangleIndexBytes;
        }
        if (need[0] > room[0] || need[1] > room[1] || need[2] > room[2]) continue;
        for (int k = 0; k < kPoolCount; ++k) room[k] -= need[k];
        kept.push_back(r);
    }
    return kept;
}

uint64_t StreamingBlocks::vertexBytes(uint32_t block) const {
    if (const auto known = vertexCounts_.find(block); known != vertexCounts_.end()) return known->second * kVertexBytes;
    const uint64_t triangles = layout().blocks[block].totalTriangles();
    // Before any block has been merged, one vertex a triangle (closed meshes share each vertex
    // among about six triangles; clipping adds some back).
    const double perTriangle = trianglesSeen_ ? double(verticesSeen_) / double(trianglesSeen_) : 1.0;
    return uint64_t(double(triangles) * perTriangle) * kVertexBytes;
}

void StreamingBlocks::noteFailure(uint32_t block, const std::string& error) {
    if (!failed_.insert(block).second) return;
    ++current_.failedBlocks;
    for (PoolKind k : {kVoxelPool, kVertexPool, kIndexPool}) pools_[k]->discard(block);
    if (warn_) warn_(error);
}

double StreamingBlocks::waitForLoads() const {
    const double t0 = raster::nowMs();
    loader_->waitForCompleted();
    return raster::nowMs() - t0;
}

bool StreamingBlocks::settled() const {
    return lastRequests_.empty() && staging_.empty() && loader_->idle();
}

}  // namespace cuberille::lod
