#include "voxel/cvox_file.h"

#include <array>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "scene/ply_loader.h"
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

uint64_t blockDataBytes(uint64_t voxels, uint64_t triangles) { return voxels * 12 + triangles * kSourceTriangleBytes; }

}  // namespace

void writeCvox(const VoxelModel& model, std::ostream& out) {
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
        h.put(uint32_t(b.voxels.size()));
        h.put(uint32_t(b.triangles.size()));
        h.put(at);
        h.put(at + b.voxels.size() * 12);
        const std::array<uint8_t, 6> tight{uint8_t(b.tightMin.x), uint8_t(b.tightMin.y), uint8_t(b.tightMin.z),
                                           uint8_t(b.tightMax.x), uint8_t(b.tightMax.y), uint8_t(b.tightMax.z)};
        h.putArray(tight.data(), tight.size());
        h.padTo(8);  // 4 + 12 + 4 + 4 + 8 + 8 + 6 = 46, padded to 48
        h.put(b.firstChild);
        h.put(uint32_t(b.childMask));
        h.put(uint64_t(0));  // reserved, to 64
        at += blockDataBytes(b.voxels.size(), b.triangles.size());
    }
    out.write(h.bytes().data(), std::streamsize(h.size()));
    for (const VoxelBlock& b : model.blocks) {
        out.write(reinterpret_cast<const char*>(b.voxels.data()), std::streamsize(b.voxels.size() * 4));
        out.write(reinterpret_cast<const char*>(b.normals.data()), std::streamsize(b.normals.size() * 4));
        out.write(reinterpret_cast<const char*>(b.colors.data()), std::streamsize(b.colors.size() * 4));
        out.write(reinterpret_cast<const char*>(b.triangles.data()), std::streamsize(b.triangles.size() * kSourceTriangleBytes));
    }
    if (!out) throw std::runtime_error("writing the voxel file failed");
}

VoxelModel readCvox(const std::filesystem::path& path) {
    const std::string bytes = scene::readFileBytes(path);
    const std::string name = path.string();
    ByteReader h(bytes, name);
    if (bytes.size() < kHeaderBytes)
        h.fail("header", "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the 96-byte header");
    const auto magic = h.get<std::array<char, 4>>("magic");
    if (std::memcmp(magic.data(), kMagic, 4) != 0) h.fail("magic", "not a voxel file (no CVOX magic)");
    const uint32_t version = h.get<uint32_t>("version");
    if (version != kVersion) h.fail("version", "unsupported version " + std::to_string(version));
    VoxelModel m;
    m.grid.resolution = h.get<uint32_t>("resolution");
    if (!isValidResolution(m.grid.resolution)) h.fail("resolution", "not a power of two from 2 to 65536");
    m.blockSize = h.get<uint32_t>("block size");
    if (m.blockSize != std::min(kBlockSize, m.grid.resolution)) h.fail("block size", "unsupported block size");
    const uint32_t levels = h.get<uint32_t>("level count");
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
    ByteReader table(std::string_view(bytes).substr(kHeaderBytes), name + ": block table", kHeaderBytes);
    if (blockCount > table.remaining() / kBlockEntryBytes)
        table.fail("block count", "truncated: " + std::to_string(blockCount) + " blocks need " +
                                      std::to_string(blockCount * kBlockEntryBytes) + " bytes of table");
    m.blocks.resize(blockCount);
    uint64_t voxelSum = 0, triangleSum = 0;
    for (uint64_t i = 0; i < blockCount; ++i) {
        VoxelBlock& b = m.blocks[i];
        const std::string where = name + ": block " + std::to_string(i);
        ByteReader e(std::string_view(bytes).substr(kHeaderBytes + i * kBlockEntryBytes, kBlockEntryBytes), where,
                     kHeaderBytes + i * kBlockEntryBytes);
        b.level = e.get<uint32_t>("level");
        if (b.level >= std::max(levels, 1u)) e.fail("level", "beyond the header's level count");
        b.coord = e.get<glm::uvec3>("coord");
        const uint32_t blocksPerAxis = std::max(1u, (m.grid.resolution >> b.level) / m.blockSize);
        if (b.coord.x >= blocksPerAxis || b.coord.y >= blocksPerAxis || b.coord.z >= blocksPerAxis)
            e.fail("coord", "block outside the grid");
        const uint32_t nv = e.get<uint32_t>("voxel count");
        const uint32_t nt = e.get<uint32_t>("triangle count");
        const uint64_t voxelOffset = e.get<uint64_t>("voxel offset");
        const uint64_t triangleOffset = e.get<uint64_t>("triangle offset");
        if (voxelOffset > bytes.size() || uint64_t(nv) * 12 > bytes.size() - voxelOffset)
            e.fail("voxel offset", "truncated: the voxels lie past the end of the file (" + std::to_string(bytes.size()) + " bytes)");
        if (triangleOffset > bytes.size() || uint64_t(nt) * kSourceTriangleBytes > bytes.size() - triangleOffset)
            e.fail("triangle offset", "truncated: the triangles lie past the end of the file (" + std::to_string(bytes.size()) + " bytes)");
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
        ByteReader data(std::string_view(bytes).substr(voxelOffset, uint64_t(nv) * 12), where, voxelOffset);
        b.voxels.resize(nv);
        b.normals.resize(nv);
        b.colors.resize(nv);
        data.getArray(b.voxels.data(), nv, "voxels");
        data.getArray(b.normals.data(), nv, "normals");
        data.getArray(b.colors.data(), nv, "colours");
        for (uint32_t v = 0; v < nv; ++v) {
            const glm::uvec3 p = voxelPositionInBlock(b.voxels[v]);
            if (p.x >= m.blockSize || p.y >= m.blockSize || p.z >= m.blockSize || (b.voxels[v] >> 30) != 0)
                data.fail("voxels", "voxel " + std::to_string(v) + " lies outside its block (corrupt)");
        }
        b.triangles.resize(nt);
        ByteReader tris(std::string_view(bytes).substr(triangleOffset, uint64_t(nt) * kSourceTriangleBytes), where,
                        triangleOffset);
        tris.getArray(b.triangles.data(), nt, "triangles");
        voxelSum += nv;
        triangleSum += nt;
    }
    if (voxelSum != voxelCount || triangleSum != triangleCount)
        throw scene::InputError(name + ": the header's voxel or triangle count does not match its blocks (corrupt)");
    return m;
}

}  // namespace cuberille::voxel
