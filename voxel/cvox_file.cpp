#include "voxel/cvox_file.h"

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "voxel/binary_io.h"

namespace cuberille::voxel {
namespace {

constexpr char kMagic[4] = {'C', 'V', 'O', 'X'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 96;
constexpr size_t kBlockEntryBytes = 64;
constexpr size_t kSourceTriangleBytes = sizeof(SourceTriangle);
static_assert(sizeof(SourceTriangle) == 60, "source triangles are stored as they are laid out");

constexpr uint32_t kFlagColors = 1u << 0, kFlagTriangles = 1u << 1;

}  // namespace

uint64_t cvoxBlockDataBytes(uint64_t voxels, uint64_t triangles) { return voxels * 12 + triangles * kSourceTriangleBytes; }

void writeCvox(const VoxelModel& model, std::ostream& out) {
    writeCvoxHeaderAndTable(model, out);
    for (const VoxelBlock& b : model.blocks) writeCvoxBlockData(b, out);
    if (!out) throw std::runtime_error("writing the voxel file failed");
}

void writeCvoxHeaderAndTable(const VoxelModel& model, std::ostream& out) {
    const uint64_t tableEnd = kHeaderBytes + kBlockEntryBytes * model.blocks.size();
    uint32_t levels = 0;
    for (const VoxelBlock& b : model.blocks) levels = std::max(levels, b.level + 1);
    ByteWriter h;
    h.putArray(kMagic, 4);
    h.put(kVersion);
    h.put(model.grid.resolution);
    h.put(model.blockSize);
    h.put(levels);
    h.put(uint32_t(model.separability));
    h.put(uint32_t((model.hasColors ? kFlagColors : 0) | (model.triangleCount() ? kFlagTriangles : 0)));
    h.put(uint32_t(0));
    h.put(model.grid.origin);
    h.put(model.grid.extent);
    h.put(uint64_t(model.blocks.size()));
    h.put(model.voxelCount());
    h.put(model.triangleCount());
    h.padTo(kHeaderBytes);
    uint64_t at = tableEnd;
    for (const VoxelBlock& b : model.blocks) {
        h.put(b.level);
        h.put(b.coord);
        h.put(uint32_t(b.totalVoxels()));
        h.put(uint32_t(b.totalTriangles()));
        h.put(at);
        h.put(at + b.totalVoxels() * 12);
        const std::array<uint8_t, 6> tight{uint8_t(b.tightMin.x), uint8_t(b.tightMin.y), uint8_t(b.tightMin.z),
                                           uint8_t(b.tightMax.x), uint8_t(b.tightMax.y), uint8_t(b.tightMax.z)};
        h.putArray(tight.data(), tight.size());
        h.padTo(8);  // 4 + 12 + 4 + 4 + 8 + 8 + 6 = 46, padded to 48
        h.put(b.firstChild);
        h.put(uint32_t(b.childMask));
        h.put(uint64_t(0));  // reserved, to 64
        at += cvoxBlockDataBytes(b.totalVoxels(), b.totalTriangles());
    }
    out.write(h.bytes().data(), std::streamsize(h.size()));
    if (!out) throw std::runtime_error("writing the voxel file failed");
}

void writeCvoxBlockData(const VoxelBlock& b, std::ostream& out) {
    out.write(reinterpret_cast<const char*>(b.voxels.data()), std::streamsize(b.voxels.size() * 4));
    out.write(reinterpret_cast<const char*>(b.normals.data()), std::streamsize(b.normals.size() * 4));
    out.write(reinterpret_cast<const char*>(b.colors.data()), std::streamsize(b.colors.size() * 4));
    out.write(reinterpret_cast<const char*>(b.triangles.data()), std::streamsize(b.triangles.size() * kSourceTriangleBytes));
}

CvoxReader::CvoxReader(const std::filesystem::path& path)
    : name_(path.string()), file_(std::make_unique<PositionalFile>(name_)), fileBytes_(file_->size()) {
    std::string head(kHeaderBytes, '\0');
    ByteReader h(head, name_);
    if (fileBytes_ < kHeaderBytes)
        h.fail("header", "truncated: " + std::to_string(fileBytes_) + " bytes, shorter than the 96-byte header");
    file_->readAt(0, head.data(), head.size(), name_);
    const auto magic = h.get<std::array<char, 4>>("magic");
    if (std::memcmp(magic.data(), kMagic, 4) != 0) h.fail("magic", "not a voxel file (no CVOX magic)");
    const uint32_t version = h.get<uint32_t>("version");
    if (version != kVersion) h.fail("version", "unsupported version " + std::to_string(version));
    VoxelModel& m = layout_;
    m.grid.resolution = h.get<uint32_t>("resolution");
    if (!isValidResolution(m.grid.resolution)) h.fail("resolution", "not a power of two from 2 to 65536");
    m.blockSize = h.get<uint32_t>("block size");
    if (m.blockSize != std::min(kBlockSize, m.grid.resolution)) h.fail("block size", "unsupported block size");
    const uint32_t levels = h.get<uint32_t>("level count");
    // A pyramid halves the grid per level until one block covers it (lod/lod_pyramid.h), so a
    // count past that is corrupt, and would shift the resolution out of range below.
    uint32_t levelLimit = 1;
    for (uint32_t r = m.grid.resolution; r > m.blockSize; r /= 2) ++levelLimit;
    if (levels > levelLimit)
        h.fail("level count", std::to_string(levels) + " levels, more than the " + std::to_string(levelLimit) +
                                  " a " + std::to_string(m.grid.resolution) + "-voxel grid can have");
    const uint32_t sep = h.get<uint32_t>("separability");
    if (sep != 0 && sep != 6 && sep != 26) h.fail("separability", "unknown value " + std::to_string(sep));
    m.separability = Separability(sep);
    const uint32_t flags = h.get<uint32_t>("flags");
    m.hasColors = flags & kFlagColors;
    h.skip(4, "reserved");
    m.grid.origin = h.get<glm::dvec3>("origin");
    m.grid.extent = h.get<double>("extent");
    if (!(m.grid.extent > 0.0) || !std::isfinite(m.grid.extent)) h.fail("extent", "not a positive number");
    const uint64_t blockCount = h.get<uint64_t>("block count");
    const uint64_t voxelCount = h.get<uint64_t>("voxel count");
    const uint64_t triangleCount = h.get<uint64_t>("triangle count");
    if (blockCount > (fileBytes_ - kHeaderBytes) / kBlockEntryBytes)
        throw scene::InputError(name_ + ": block table at byte 96 (block count): truncated: " +
                                std::to_string(blockCount) + " blocks need " +
                                std::to_string(blockCount * kBlockEntryBytes) + " bytes of table");
    std::string table(blockCount * kBlockEntryBytes, '\0');
    file_->readAt(kHeaderBytes, table.data(), table.size(), name_ + ": block table");
    m.blocks.resize(blockCount);
    offsets_.resize(blockCount);
    uint64_t voxelSum = 0, triangleSum = 0;
    for (uint64_t i = 0; i < blockCount; ++i) {
        VoxelBlock& b = m.blocks[i];
        const std::string where = name_ + ": block " + std::to_string(i);
        ByteReader e(std::string_view(table).substr(i * kBlockEntryBytes, kBlockEntryBytes), where,
                     kHeaderBytes + i * kBlockEntryBytes);
        b.level = e.get<uint32_t>("level");
        if (b.level >= std::max(levels, 1u)) e.fail("level", "beyond the header's level count");
        b.coord = e.get<glm::uvec3>("coord");
        const uint32_t blocksPerAxis = std::max(1u, (m.grid.resolution >> b.level) / m.blockSize);
        if (b.coord.x >= blocksPerAxis || b.coord.y >= blocksPerAxis || b.coord.z >= blocksPerAxis)
            e.fail("coord", "block outside the grid");
        BlockData& d = offsets_[i];
        d.voxels = e.get<uint32_t>("voxel count");
        d.triangles = e.get<uint32_t>("triangle count");
        d.voxelOffset = e.get<uint64_t>("voxel offset");
        d.triangleOffset = e.get<uint64_t>("triangle offset");
        if (d.voxelOffset > fileBytes_ || uint64_t(d.voxels) * 12 > fileBytes_ - d.voxelOffset)
            e.fail("voxel offset", "truncated: the voxels lie past the end of the file (" + std::to_string(fileBytes_) + " bytes)");
        if (d.triangleOffset > fileBytes_ || uint64_t(d.triangles) * kSourceTriangleBytes > fileBytes_ - d.triangleOffset)
            e.fail("triangle offset", "truncated: the triangles lie past the end of the file (" + std::to_string(fileBytes_) + " bytes)");
        const auto tight = e.get<std::array<uint8_t, 6>>("tight bounds");
        b.tightMin = {tight[0], tight[1], tight[2]};
        b.tightMax = {tight[3], tight[4], tight[5]};
        e.skip(2, "padding");
        b.firstChild = e.get<uint32_t>("first child");
        const uint32_t mask = e.get<uint32_t>("child mask");
        if (mask > 0xFF || (mask && b.level == 0) ||
            uint64_t(b.firstChild) + uint64_t(__builtin_popcount(mask)) > blockCount || (mask && b.firstChild <= i))
            e.fail("child mask", "child links outside the block table (corrupt)");
        b.childMask = uint8_t(mask);
        b.layoutVoxels = d.voxels;
        b.layoutTriangles = d.triangles;
        voxelSum += d.voxels;
        triangleSum += d.triangles;
    }
    if (voxelSum != voxelCount || triangleSum != triangleCount)
        throw scene::InputError(name_ + ": the header's voxel or triangle count does not match its blocks (corrupt)");
}

CvoxReader::~CvoxReader() = default;

uint64_t CvoxReader::partBytes(size_t i, Parts parts) const {
    const BlockData& d = offsets_.at(i);
    return ((parts & kVoxels) ? uint64_t(d.voxels) * 12 : 0) +
           ((parts & kTriangles) ? uint64_t(d.triangles) * kSourceTriangleBytes : 0);
}

VoxelBlock CvoxReader::load(size_t i, Parts parts) const {
    VoxelBlock b = layout_.blocks[i];
    b.layoutVoxels = b.layoutTriangles = 0;  // a loaded block's counts are its arrays'
    const BlockData& d = offsets_[i];
    const std::string where = name_ + ": block " + std::to_string(i);
    if (parts & kTriangles) {
        b.triangles.resize(d.triangles);
        if (d.triangles)
            file_->readAt(d.triangleOffset, reinterpret_cast<char*>(b.triangles.data()),
                          size_t(d.triangles) * kSourceTriangleBytes, where);
    }
    if (!(parts & kVoxels)) return b;
    std::string bytes(size_t(d.voxels) * 12, '\0');
    file_->readAt(d.voxelOffset, bytes.data(), bytes.size(), where);
    ByteReader data(bytes, where, d.voxelOffset);
    b.voxels.resize(d.voxels);
    b.normals.resize(d.voxels);
    b.colors.resize(d.voxels);
    data.getArray(b.voxels.data(), d.voxels, "voxels");
    data.getArray(b.normals.data(), d.voxels, "normals");
    data.getArray(b.colors.data(), d.voxels, "colours");
    for (uint32_t v = 0; v < d.voxels; ++v) {
        const glm::uvec3 p = voxelPositionInBlock(b.voxels[v]);
        if (p.x >= layout_.blockSize || p.y >= layout_.blockSize || p.z >= layout_.blockSize || (b.voxels[v] >> 30) != 0)
            data.fail("voxels", "voxel " + std::to_string(v) + " lies outside its block (corrupt)");
    }
    return b;
}

VoxelModel readCvox(const std::filesystem::path& path) {
    const CvoxReader reader(path);
    VoxelModel m = reader.layout();
    for (size_t i = 0; i < m.blocks.size(); ++i) m.blocks[i] = reader.load(i);  // counts cleared by load
    return m;
}

}  // namespace cuberille::voxel
