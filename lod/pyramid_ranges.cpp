#include "lod/pyramid_ranges.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "raster/clock.h"
#include "scene/input_error.h"
#include "voxel/binary_io.h"
#include "voxel/cvox_file.h"
#include "voxel/morton.h"
#include "voxel/voxel_export.h"

namespace cuberille::lod {
namespace {

using voxel::VoxelBlock;

// A range file: a working file between a worker and the join, read back by the same build.
//   "CVXR" u32 version, u32 split level, u32 block size, u64 skirt faces, u64 hidden faces cleared,
//   u64 finished blocks, u64 level-S copies
//   table, per block (finished ones coarsest level first, Morton within a level; then the copies):
//     u32 level, u32 coord[3], u32 voxels, u32 triangles, u32 tight min[3], u32 tight max[3],
//     u64 data offset
//   data, per block: voxels, normals, colours, source triangles (a .cvox block's bytes)
constexpr char kMagic[4] = {'C', 'V', 'X', 'R'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 48;
constexpr size_t kEntryBytes = 56;

struct RangeEntry {
    uint32_t level = 0, voxels = 0, triangles = 0;
    glm::uvec3 coord{0}, tightMin{0}, tightMax{0};
    uint64_t offset = 0;
};

/// Distinct subtrees of level l among sorted, distinct level-0 codes.
size_t subtreesAt(const std::vector<uint64_t>& codes, uint32_t level) {
    size_t n = 0;
    for (size_t i = 0; i < codes.size(); ++i)
        if (i == 0 || codes[i] >> (3 * level) != codes[i - 1] >> (3 * level)) ++n;
    return n;
}

void writeRangeFile(const std::vector<VoxelBlock*>& finished, const std::vector<VoxelBlock*>& copies,
                    uint32_t splitLevel, uint32_t blockSize, const PyramidStats& faces, std::ostream& out) {
    voxel::ByteWriter w;
    w.putArray(kMagic, 4);
    w.put(kVersion);
    w.put(splitLevel);
    w.put(blockSize);
    w.put(faces.skirtFaces);
    w.put(faces.hiddenFacesCleared);
    w.put(uint64_t(finished.size()));
    w.put(uint64_t(copies.size()));
    uint64_t at = kHeaderBytes + kEntryBytes * (finished.size() + copies.size());
    auto entry = [&](const VoxelBlock& b) {
        w.put(b.level);
        w.put(b.coord);
        w.put(uint32_t(b.voxels.size()));
        w.put(uint32_t(b.triangles.size()));
        w.put(b.tightMin);
        w.put(b.tightMax);
        w.put(at);
        at += voxel::cvoxBlockDataBytes(b.voxels.size(), b.triangles.size());
    };
    for (const VoxelBlock* b : finished) entry(*b);
    for (const VoxelBlock* b : copies) entry(*b);
    out.write(w.bytes().data(), std::streamsize(w.size()));
    for (const VoxelBlock* b : finished) voxel::writeCvoxBlockData(*b, out);
    for (const VoxelBlock* b : copies) voxel::writeCvoxBlockData(*b, out);
    if (!out) throw std::runtime_error("writing the range file failed");
}

/// A block with the entry's level, coordinates and bounds, and no data.
VoxelBlock layoutOf(const RangeEntry& e) {
    VoxelBlock b;
    b.level = e.level, b.coord = e.coord, b.tightMin = e.tightMin, b.tightMax = e.tightMax;
    return b;
}

/// A block's data read back into its arrays; what simplification relies on is checked: every
/// voxel inside its block.
VoxelBlock loadBlock(const voxel::PositionalFile& file, const RangeEntry& e, uint32_t blockSize) {
    VoxelBlock b = layoutOf(e);
    b.voxels.resize(e.voxels), b.normals.resize(e.voxels), b.colors.resize(e.voxels), b.triangles.resize(e.triangles);
    const std::string where = file.name() + ": block data";
    file.readAt(e.offset, reinterpret_cast<char*>(b.voxels.data()), e.voxels * 4, where);
    file.readAt(e.offset + e.voxels * 4, reinterpret_cast<char*>(b.normals.data()), e.voxels * 4, where);
    file.readAt(e.offset + e.voxels * 8, reinterpret_cast<char*>(b.colors.data()), e.voxels * 4, where);
    file.readAt(e.offset + e.voxels * 12, reinterpret_cast<char*>(b.triangles.data()), e.triangles * sizeof(voxel::SourceTriangle),
                where);
    for (uint32_t packed : b.voxels) {
        const glm::uvec3 p = voxel::voxelPositionInBlock(packed);
        if (p.x >= blockSize || p.y >= blockSize || p.z >= blockSize)
            throw scene::InputError(where + " at byte " + std::to_string(e.offset) + ": a voxel outside its block");
    }
    return b;
}

}  // namespace

PyramidRangePlan planPyramidRanges(std::vector<std::pair<uint64_t, uint64_t>> blocks, uint32_t levels,
                                   size_t wantedRanges) {
    PyramidRangePlan plan;
    plan.levels = std::max(levels, 1u);
    std::sort(blocks.begin(), blocks.end());
    std::vector<uint64_t> codes;
    for (const auto& [code, weight] : blocks)
        if (codes.empty() || codes.back() != code) codes.push_back(code);
    if (codes.empty() || wantedRanges <= 1) {  // one range: it builds every level, the join copies
        plan.splitLevel = plan.levels - 1;
        return plan;
    }
    const size_t enough = std::min(2 * wantedRanges, codes.size());
    for (uint32_t l = plan.levels; l-- > 0;)
        if (subtreesAt(codes, l) >= enough) {
            plan.splitLevel = l;
            break;
        }
    // The subtrees of level S with their weights, in Morton order; cut where the weight before a
    // subtree first reaches the next k/wanted of the whole.
    const uint32_t shift = 3 * plan.splitLevel;
    std::vector<std::pair<uint64_t, uint64_t>> subtrees;
    uint64_t total = 0;
    for (const auto& [code, weight] : blocks) {
        if (subtrees.empty() || subtrees.back().first != code >> shift) subtrees.push_back({code >> shift, 0});
        subtrees.back().second += weight;
        total += weight;
    }
    uint64_t before = 0;
    size_t next = 1;
    for (const auto& [subtree, weight] : subtrees) {
        if (next < wantedRanges && before > 0 && before * wantedRanges >= total * next) {
            plan.rangeStarts.push_back(subtree << shift);
            while (next < wantedRanges && before * wantedRanges >= total * next) ++next;
        }
        before += weight;
    }
    return plan;
}

PyramidStats buildPyramidRange(voxel::VoxelModel range, const PyramidOptions& options, uint32_t splitLevel,
                               std::ostream& out) {
    const uint32_t levels = pyramidLevels(range.grid.resolution, range.blockSize, options);
    if (splitLevel >= levels) throw std::invalid_argument("buildPyramidRange: split level above the pyramid's top");
    std::vector<std::vector<VoxelBlock>> pyramid(1);
    pyramid[0] = std::move(range.blocks);
    for (uint32_t l = 1; l <= splitLevel; ++l) pyramid.push_back(simplifyLevel(pyramid[l - 1], range.blockSize, options.method));
    // The level above S is built by the join from the level-S blocks as simplification left them.
    std::vector<VoxelBlock> copies;
    if (splitLevel + 1 < levels) {
        copies = pyramid[splitLevel];
        for (VoxelBlock& b : copies) b.triangles.clear();  // simplification reads voxels only
    }
    PyramidStats stats;
    std::vector<VoxelBlock*> finished, copied;
    for (uint32_t l = splitLevel + 1; l-- > 0;) {
        finishBlockFaces(pyramid[l], range.blockSize, options.clearHiddenFaces, stats);
        for (VoxelBlock& b : pyramid[l]) finished.push_back(&b);
    }
    for (VoxelBlock& b : copies) copied.push_back(&b);
    writeRangeFile(finished, copied, splitLevel, range.blockSize, stats, out);
    return stats;
}

PyramidRangeJoin::PyramidRangeJoin(const voxel::VoxelModel& header, const std::vector<std::filesystem::path>& rangeFiles,
                                   const PyramidOptions& options, const PyramidRangePlan& plan) {
    const double t0 = raster::nowMs();
    const uint32_t levels = pyramidLevels(header.grid.resolution, header.blockSize, options);
    const uint32_t split = plan.splitLevel;
    if (plan.levels != levels || split >= levels)
        throw std::invalid_argument("PyramidRangeJoin: a plan for another pyramid");
    // Each range's finished blocks by level, and its level-S copies.
    std::vector<std::vector<std::vector<RangeEntry>>> finished(rangeFiles.size(), std::vector<std::vector<RangeEntry>>(split + 1));
    std::vector<std::vector<RangeEntry>> copies(rangeFiles.size());
    for (size_t r = 0; r < rangeFiles.size(); ++r) {
        files_.push_back(std::make_unique<voxel::PositionalFile>(rangeFiles[r].string()));
        const voxel::PositionalFile& file = *files_.back();
        std::string head(kHeaderBytes, '\0');
        voxel::ByteReader h(head, file.name());
        if (file.size() < kHeaderBytes) h.fail("header", "truncated: " + std::to_string(file.size()) + " bytes");
        file.readAt(0, head.data(), head.size(), file.name());
        char magic[4];
        h.getArray(magic, 4, "magic");
        if (std::memcmp(magic, kMagic, 4) != 0) h.fail("magic", "not a pyramid range (CVXR)");
        if (h.get<uint32_t>("version") != kVersion) h.fail("version", "written by another version");
        if (h.get<uint32_t>("split level") != split) h.fail("split level", "not the plan's");
        if (h.get<uint32_t>("block size") != header.blockSize) h.fail("block size", "not the model's");
        stats_.skirtFaces += h.get<uint64_t>("skirt faces");
        stats_.hiddenFacesCleared += h.get<uint64_t>("hidden faces");
        const uint64_t finishedCount = h.get<uint64_t>("finished blocks");
        const uint64_t copyCount = h.get<uint64_t>("level copies");
        if (finishedCount + copyCount > (file.size() - kHeaderBytes) / kEntryBytes)
            h.fail("block counts", "the table does not fit in the file");
        std::string tableBytes((finishedCount + copyCount) * kEntryBytes, '\0');
        file.readAt(kHeaderBytes, tableBytes.data(), tableBytes.size(), file.name());
        voxel::ByteReader t(tableBytes, file.name() + ": block table", kHeaderBytes);
        for (uint64_t i = 0; i < finishedCount + copyCount; ++i) {
            RangeEntry e;
            e.level = t.get<uint32_t>("level");
            e.coord = t.get<glm::uvec3>("coordinates");
            e.voxels = t.get<uint32_t>("voxel count");
            e.triangles = t.get<uint32_t>("triangle count");
            e.tightMin = t.get<glm::uvec3>("bounds");
            e.tightMax = t.get<glm::uvec3>("bounds");
            e.offset = t.get<uint64_t>("data offset");
            if (e.offset > file.size() || voxel::cvoxBlockDataBytes(e.voxels, e.triangles) > file.size() - e.offset)
                t.fail("data offset", "the block's data lies past the end of the file");
            if (e.level > split || (i >= finishedCount && e.level != split)) t.fail("level", "not the plan's levels");
            const uint32_t blocksPerSide = std::max(1u, (header.grid.resolution / header.blockSize) >> e.level);
            if (e.coord.x >= blocksPerSide || e.coord.y >= blocksPerSide || e.coord.z >= blocksPerSide)
                t.fail("coordinates", "outside the grid's " + std::to_string(blocksPerSide) + " blocks a side at level " +
                                          std::to_string(e.level));
            (i < finishedCount ? finished[r][e.level] : copies[r]).push_back(e);
        }
    }
    // Levels above S, from the copies of level S.
    std::vector<std::vector<VoxelBlock>> above;
    if (split + 1 < levels) {
        std::vector<VoxelBlock> level;
        for (size_t r = 0; r < copies.size(); ++r)
            for (const RangeEntry& e : copies[r]) level.push_back(loadBlock(*files_[r], e, header.blockSize));
        for (uint32_t l = split + 1; l < levels; ++l) {
            std::vector<VoxelBlock> next = simplifyLevel(l == split + 1 ? level : above.back(), header.blockSize, options.method);
            above.push_back(std::move(next));
        }
    }
    layout_ = header;
    layout_.blocks.clear();
    for (size_t l = above.size(); l-- > 0;)
        for (VoxelBlock& b : above[l]) layout_.blocks.push_back(std::move(b));
    loadedBlocks_ = layout_.blocks.size();
    finishBlockFaces(std::span(layout_.blocks).first(loadedBlocks_), header.blockSize, options.clearHiddenFaces, stats_);
    for (uint32_t l = split + 1; l-- > 0;)
        for (size_t r = 0; r < finished.size(); ++r)
            for (const RangeEntry& e : finished[r][l]) {
                VoxelBlock b = layoutOf(e);
                b.layoutVoxels = e.voxels, b.layoutTriangles = e.triangles;
                if (layout_.blocks.size() > loadedBlocks_ && layout_.blocks.back().level == b.level &&
                    voxel::mortonOf(layout_.blocks.back().coord) >= voxel::mortonOf(b.coord))
                    throw scene::InputError(files_[r]->name() + ": block table: blocks out of Morton order with the "
                                            "ranges before it (the range files must be given in the plan's order)");
                layout_.blocks.push_back(std::move(b));
                stored_.push_back({uint32_t(r), e.offset});
            }
    linkChildren(layout_.blocks);
    stats_.levels = levels;
    stats_.blocksPerLevel.assign(levels, 0);
    stats_.voxelsPerLevel.assign(levels, 0);
    for (const VoxelBlock& b : layout_.blocks) ++stats_.blocksPerLevel[b.level], stats_.voxelsPerLevel[b.level] += b.totalVoxels();
    stats_.simplifyMs = raster::nowMs() - t0;
}

PyramidRangeJoin::~PyramidRangeJoin() = default;

void PyramidRangeJoin::write(std::ostream& cvox, std::ostream* exportVoxels) const {
    voxel::writeCvoxHeaderAndTable(layout_, cvox);
    for (size_t i = 0; i < loadedBlocks_; ++i) voxel::writeCvoxBlockData(layout_.blocks[i], cvox);
    // The rest a piece at a time: the join never holds more than this of the finer levels.
    constexpr size_t kCopyBytes = size_t(4) << 20;
    std::string buffer;
    for (size_t i = loadedBlocks_; i < layout_.blocks.size(); ++i) {
        const VoxelBlock& b = layout_.blocks[i];
        const Stored& s = stored_[i - loadedBlocks_];
        const uint64_t bytes = voxel::cvoxBlockDataBytes(b.totalVoxels(), b.totalTriangles());
        for (uint64_t done = 0; done < bytes;) {
            const size_t n = size_t(std::min<uint64_t>(kCopyBytes, bytes - done));
            buffer.resize(n);
            files_[s.file]->readAt(s.offset + done, buffer.data(), n, files_[s.file]->name() + ": block data");
            cvox.write(buffer.data(), std::streamsize(n));
            done += n;
        }
    }
    if (!cvox) throw std::runtime_error("writing the voxel file failed");
    if (!exportVoxels) return;
    voxel::writeVoxelExportHeader(layout_.grid, *exportVoxels);
    std::string text;
    for (size_t i = loadedBlocks_; i < layout_.blocks.size(); ++i) {
        const VoxelBlock& b = layout_.blocks[i];
        if (b.level != 0) continue;
        const Stored& s = stored_[i - loadedBlocks_];
        VoxelBlock voxels;
        voxels.coord = b.coord;
        voxels.voxels.resize(b.totalVoxels());
        files_[s.file]->readAt(s.offset, reinterpret_cast<char*>(voxels.voxels.data()), voxels.voxels.size() * 4,
                               files_[s.file]->name() + ": block data");
        voxel::appendVoxelExportLines(voxels, layout_.blockSize, text);
        if (text.size() > (1u << 20)) {
            *exportVoxels << text;
            text.clear();
        }
    }
    *exportVoxels << text;
    if (!*exportVoxels) throw std::runtime_error("writing the voxel export failed");
}

}  // namespace cuberille::lod
