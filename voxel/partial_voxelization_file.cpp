#include "voxel/partial_voxelization_file.h"

#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>

#include "voxel/binary_io.h"
#include "voxel/morton.h"

namespace cuberille::voxel {
namespace {

constexpr char kMagic[4] = {'C', 'V', 'X', 'P'};
constexpr uint32_t kVersion = 2;  // 2: the part's winding sums after its chunk range
static_assert(sizeof(SourceTriangle) == 60, "source triangles are written as their 60 bytes");

void putBlock(ByteWriter& w, const BlockPartial& b, bool withColors) {
    w.putArray(&b.coord.x, 3);
    w.put(uint64_t(b.leaves.size()));
    w.putArray(b.leafMorton.data(), b.leafMorton.size());
    for (const LeafSums& s : b.leaves) {  // field by field: the struct's padding is not data
        w.putArray(s.normal, 3);
        w.put(s.weight);
        w.put(s.faceMask);
        w.put(s.targets);
    }
    if (withColors)
        for (const LeafColorSums& c : b.colors) w.putArray(c.rgb, 3);
    w.put(uint64_t(b.triangles.size()));
    w.putArray(b.triangleKeys.data(), b.triangleKeys.size());
    w.putArray(b.triangles.data(), b.triangles.size());
}

// What the merge relies on is checked here: a block inside the grid, leaves inside the block in
// ascending order, triangle keys ascending.
BlockPartial getBlock(ByteReader& r, const VoxelModel& header) {
    const bool withColors = header.hasColors;
    const uint32_t blocksPerSide = header.grid.resolution / header.blockSize;
    const uint32_t leavesPerBlock = header.blockSize * header.blockSize * header.blockSize;
    BlockPartial b;
    r.getArray(&b.coord.x, 3, "block coordinates");
    if (b.coord.x >= blocksPerSide || b.coord.y >= blocksPerSide || b.coord.z >= blocksPerSide)
        r.fail("block coordinates", "outside the grid's " + std::to_string(blocksPerSide) + " blocks a side");
    const uint64_t leaves = r.get<uint64_t>("leaf count");
    if (leaves > r.remaining() / 4) r.fail("leaf count", std::to_string(leaves) + " leaves do not fit in the file");
    b.leafMorton.resize(leaves);
    r.getArray(b.leafMorton.data(), leaves, "leaf positions");
    for (size_t i = 0; i < leaves; ++i)
        if (b.leafMorton[i] >= leavesPerBlock || (i > 0 && b.leafMorton[i] <= b.leafMorton[i - 1]))
            r.fail("leaf positions", "leaf " + std::to_string(i) + " outside the block or out of order");
    b.leaves.resize(leaves);
    for (LeafSums& s : b.leaves) {
        r.getArray(s.normal, 3, "leaf normal sums");
        s.weight = r.get<int64_t>("leaf weight");
        s.faceMask = r.get<uint8_t>("leaf faces");
        s.targets = r.get<uint8_t>("leaf targets");
    }
    if (withColors) {
        b.colors.resize(leaves);
        for (LeafColorSums& c : b.colors) r.getArray(c.rgb, 3, "leaf colour sums");
    }
    const uint64_t triangles = r.get<uint64_t>("triangle count");
    if (triangles > r.remaining() / 68) r.fail("triangle count", std::to_string(triangles) + " triangles do not fit in the file");
    b.triangleKeys.resize(triangles);
    r.getArray(b.triangleKeys.data(), triangles, "triangle keys");
    for (size_t i = 1; i < triangles; ++i)
        if (b.triangleKeys[i] <= b.triangleKeys[i - 1]) r.fail("triangle keys", "out of order at " + std::to_string(i));
    b.triangles.resize(triangles);
    r.getArray(b.triangles.data(), triangles, "source triangles");
    return b;
}

/// The magic, version and header; returns the block count.
uint64_t getHeader(ByteReader& r, PartialVoxelization& part) {
    char magic[4];
    r.getArray(magic, 4, "magic");
    if (std::string_view(magic, 4) != std::string_view(kMagic, 4)) r.fail("magic", "not a partial voxelization (CVXP)");
    if (r.get<uint32_t>("version") != kVersion) r.fail("version", "written by another version");
    VoxelModel& h = part.header;
    h.grid.resolution = r.get<uint32_t>("resolution");
    r.getArray(&h.grid.origin.x, 3, "origin");
    h.grid.extent = r.get<double>("extent");
    if (!isValidResolution(h.grid.resolution)) r.fail("resolution", std::to_string(h.grid.resolution) + " is not a valid resolution");
    if (!(h.grid.extent > 0.0) || !std::isfinite(h.grid.extent) || !std::isfinite(h.grid.origin.x) ||
        !std::isfinite(h.grid.origin.y) || !std::isfinite(h.grid.origin.z))
        r.fail("grid", "not a finite grid");
    h.blockSize = r.get<uint32_t>("block size");
    if (h.blockSize != std::min(kBlockSize, h.grid.resolution)) r.fail("block size", "not the resolution's");
    const uint32_t separability = r.get<uint32_t>("separability");
    if (separability != 0 && separability != 6 && separability != 26)
        r.fail("separability", "unknown value " + std::to_string(separability));
    h.separability = Separability(separability);
    h.hasColors = r.get<uint8_t>("colours") != 0;
    part.firstChunk = r.get<uint64_t>("first chunk");
    part.chunkCount = r.get<uint64_t>("chunk count");
    part.winding.volume = r.get<uint64_t>("winding volume");
    for (uint64_t& a : part.winding.area) a = r.get<uint64_t>("winding area");
    const uint64_t blocks = r.get<uint64_t>("block count");
    if (blocks > r.remaining() / 28) r.fail("block count", std::to_string(blocks) + " blocks do not fit in the file");
    return blocks;
}

/// The Morton code of the next block's coordinates, without moving past them.
uint64_t peekBlockMorton(const ByteReader& r, const VoxelModel& header) {
    ByteReader ahead = r;
    glm::uvec3 coord;
    ahead.getArray(&coord.x, 3, "block coordinates");
    const uint32_t blocksPerSide = header.grid.resolution / header.blockSize;
    if (coord.x >= blocksPerSide || coord.y >= blocksPerSide || coord.z >= blocksPerSide)
        ahead.fail("block coordinates", "outside the grid's " + std::to_string(blocksPerSide) + " blocks a side");
    return mortonOf(coord);
}

/// Moves past a block by its counts (the layout putBlock writes).
void skipBlock(ByteReader& r, const VoxelModel& header) {
    r.skip(12, "block coordinates");
    const uint64_t leaves = r.get<uint64_t>("leaf count");
    const uint64_t leafBytes = 4 + 3 * 8 + 8 + 1 + 1 + (header.hasColors ? 3 * 8 : 0);
    if (leaves > r.remaining() / leafBytes) r.fail("leaf count", std::to_string(leaves) + " leaves do not fit in the file");
    r.skip(size_t(leaves * leafBytes), "leaves");
    const uint64_t triangles = r.get<uint64_t>("triangle count");
    if (triangles > r.remaining() / 68) r.fail("triangle count", std::to_string(triangles) + " triangles do not fit in the file");
    r.skip(size_t(triangles * 68), "source triangles");
}

/// A whole file mapped read-only for the reader's lifetime.
class MappedFile {
public:
    explicit MappedFile(const std::filesystem::path& path) {
        const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) throw scene::InputError(path.string() + ": cannot open file: " + std::strerror(errno));
        const off_t size = ::lseek(fd, 0, SEEK_END);
        size_ = size > 0 ? size_t(size) : 0;
        if (size_ > 0) data_ = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
        ::close(fd);
        if (data_ == MAP_FAILED) throw scene::InputError(path.string() + ": cannot map file: " + std::strerror(errno));
    }
    ~MappedFile() {
        if (data_ && data_ != MAP_FAILED) ::munmap(data_, size_);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    std::string_view bytes() const { return data_ ? std::string_view(static_cast<const char*>(data_), size_) : std::string_view(); }

private:
    void* data_ = nullptr;
    size_t size_ = 0;
};

/// Reads a part's header into `part`, then hands each block, in order, to visit(reader at the
/// block, its Morton code), which reads it or steps over it; the blocks' order and the file's end
/// are checked here. Mapped, not read into a buffer: a part is hundreds of MiB, and a buffer costs
/// its zeroing and a copy (most of the merge's time, measured on the dragon at 2048^3: 463 MiB of
/// parts); the pages of blocks stepped over are never touched.
template <class VisitBlock>
void walkPart(const std::filesystem::path& path, PartialVoxelization& part, VisitBlock&& visit) {
    const MappedFile file(path);
    ByteReader r(file.bytes(), path.string());
    const uint64_t blocks = getHeader(r, part);
    uint64_t previous = 0;
    for (uint64_t i = 0; i < blocks; ++i) {
        const uint64_t morton = peekBlockMorton(r, part.header);
        if (i > 0 && morton <= previous) r.fail("block coordinates", "block " + std::to_string(i) + " out of order");
        previous = morton;
        visit(r, morton);
    }
    if (r.remaining() != 0) r.fail("end", std::to_string(r.remaining()) + " bytes after the last block");
}

}  // namespace

void writePartialVoxelization(const PartialVoxelization& part, std::ostream& out) {
    ByteWriter w;
    const VoxelModel& h = part.header;
    w.putArray(kMagic, 4);
    w.put(kVersion);
    w.put(h.grid.resolution);
    w.putArray(&h.grid.origin.x, 3);
    w.put(h.grid.extent);
    w.put(h.blockSize);
    w.put(uint32_t(h.separability));
    w.put(uint8_t(h.hasColors));
    w.put(part.firstChunk);
    w.put(part.chunkCount);
    w.put(part.winding.volume);
    for (const uint64_t a : part.winding.area) w.put(a);
    w.put(uint64_t(part.blocks.size()));
    // A block at a time to the stream: a part of a large model is hundreds of MiB, not to be
    // built whole in memory first.
    for (const BlockPartial& b : part.blocks) {
        putBlock(w, b, h.hasColors);
        out.write(w.bytes().data(), std::streamsize(w.size()));
        w.bytes().clear();
    }
    out.write(w.bytes().data(), std::streamsize(w.size()));
}

PartialVoxelization readPartialVoxelization(const std::filesystem::path& path, uint64_t mortonBegin, uint64_t mortonEnd) {
    PartialVoxelization part;
    walkPart(path, part, [&](ByteReader& r, uint64_t morton) {
        if (morton >= mortonBegin && morton < mortonEnd) part.blocks.push_back(getBlock(r, part.header));
        else skipBlock(r, part.header);
    });
    return part;
}

PartialVoxelizationIndex readPartialVoxelizationIndex(const std::filesystem::path& path) {
    PartialVoxelizationIndex index;
    walkPart(path, index.part, [&](ByteReader& r, uint64_t morton) {
        const size_t before = r.remaining();
        skipBlock(r, index.part.header);
        index.blocks.push_back({morton, before - r.remaining()});
    });
    return index;
}

}  // namespace cuberille::voxel
