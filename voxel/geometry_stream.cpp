#include "voxel/geometry_stream.h"

#include <array>
#include <cstring>
#include <stdexcept>

#include <lz4frame.h>

#include "voxel/binary_io.h"
#include "voxel/packing.h"

namespace cuberille::voxel {
namespace {

constexpr char kFileMagic[4] = {'C', 'G', 'S', '1'};
constexpr char kChunkMagic[4] = {'C', 'H', 'N', 'K'};
constexpr uint32_t kVersion = 1;
constexpr size_t kFileHeaderBytes = 32;
constexpr size_t kChunkHeaderBytes = 64;

enum ChunkFlags : uint32_t { kHasColors = 1u << 0, kIndices16 = 1u << 1 };

/// The raw payload size implied by a chunk's counts and flags: the reader's first check.
uint64_t rawPayloadBytes(uint64_t vertices, uint64_t triangles, uint32_t flags) {
    uint64_t n = vertices * (12 + 4);
    if (flags & kHasColors) n += (vertices * 3 + 3) / 4 * 4;
    n += triangles * 3 * ((flags & kIndices16) ? 2 : 4);
    return n;
}

std::string serializePayload(const GeometryChunk& c, uint32_t flags) {
    ByteWriter w;
    w.putArray(c.positions.data(), c.positions.size());
    for (const glm::vec3& n : c.normals) w.put(packNormal1010102(n));
    if (flags & kHasColors) {
        for (const glm::vec3& col : c.colors) {
            const std::array<uint8_t, 3> rgb{raster::encodeSrgb8(col.r), raster::encodeSrgb8(col.g), raster::encodeSrgb8(col.b)};
            w.putArray(rgb.data(), 3);
        }
        w.padTo(4);
    }
    if (flags & kIndices16) {
        for (uint32_t i : c.indices) w.put(uint16_t(i));
    } else {
        w.putArray(c.indices.data(), c.indices.size());
    }
    return std::move(w.bytes());
}

std::vector<char> compressFrame(const std::string& raw) {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
    prefs.frameInfo.contentSize = raw.size();
    std::vector<char> out(LZ4F_compressFrameBound(raw.size(), &prefs));
    const size_t n = LZ4F_compressFrame(out.data(), out.size(), raw.data(), raw.size(), &prefs);
    if (LZ4F_isError(n)) throw std::runtime_error(std::string("LZ4 compression failed: ") + LZ4F_getErrorName(n));
    out.resize(n);
    return out;
}

/// Decompresses one whole frame into exactly rawBytes; any error, a short or long result, or a
/// checksum mismatch is reported through fail.
template <class Fail>
std::vector<char> decompressFrame(const std::vector<char>& compressed, size_t rawBytes, Fail&& fail) {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) fail("cannot create an LZ4 context");
    std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> guard(ctx, LZ4F_freeDecompressionContext);
    std::vector<char> raw(rawBytes);
    size_t srcAt = 0, dstAt = 0;
    size_t hint = 1;
    while (hint != 0) {
        if (srcAt >= compressed.size()) fail("compressed data ends inside the LZ4 frame");
        size_t dstSize = raw.size() - dstAt, srcSize = compressed.size() - srcAt;
        hint = LZ4F_decompress(ctx, raw.data() + dstAt, &dstSize, compressed.data() + srcAt, &srcSize, nullptr);
        if (LZ4F_isError(hint)) fail(std::string("corrupt LZ4 data: ") + LZ4F_getErrorName(hint));
        srcAt += srcSize;
        dstAt += dstSize;
        if (dstSize == 0 && srcSize == 0 && hint != 0) fail("LZ4 frame holds more data than the header says");
    }
    if (dstAt != rawBytes || srcAt != compressed.size()) fail("LZ4 frame size does not match the chunk header");
    return raw;
}

struct ChunkLocation {
    uint64_t payloadOffset = 0;
    uint32_t flags = 0, rawBytes = 0, compressedBytes = 0;
};

class GeometryStreamView final : public MeshView {
public:
    explicit GeometryStreamView(const std::filesystem::path& path)
        : name_(path.string()), file_(name_), fileBytes_(file_.size()) {
        readHeaders();
    }

    size_t chunkCount() const override { return infos_.size(); }
    const ChunkInfo& chunkInfo(size_t chunk) const override { return infos_[chunk]; }
    const std::string& sourceName() const override { return name_; }

    GeometryChunk readChunk(size_t chunk) const override {
        const ChunkLocation& loc = locations_[chunk];
        const ChunkInfo& info = infos_[chunk];
        const std::string where = name_ + ": chunk " + std::to_string(chunk);
        auto fail = [&](const std::string& problem) -> void {
            throw scene::InputError(where + " at byte " + std::to_string(loc.payloadOffset) + ": " + problem);
        };
        std::vector<char> compressed(loc.compressedBytes);
        file_.readAt(loc.payloadOffset, compressed.data(), compressed.size(), where);
        const std::vector<char> raw = decompressFrame(compressed, loc.rawBytes, fail);

        GeometryChunk c;
        ByteReader r(std::string_view(raw.data(), raw.size()), where + " (decompressed)");
        c.positions.resize(info.vertexCount);
        r.getArray(c.positions.data(), c.positions.size(), "positions");
        c.normals.resize(info.vertexCount);
        for (glm::vec3& n : c.normals) n = unpackNormal1010102(r.get<uint32_t>("normals"));
        if (loc.flags & kHasColors) {
            std::vector<uint8_t> rgb(size_t(info.vertexCount) * 3);
            r.getArray(rgb.data(), rgb.size(), "colours");
            r.alignTo(4, "colour padding");
            c.colors.resize(info.vertexCount);
            for (size_t v = 0; v < c.colors.size(); ++v)
                c.colors[v] = {raster::decodeSrgb8(rgb[3 * v]), raster::decodeSrgb8(rgb[3 * v + 1]), raster::decodeSrgb8(rgb[3 * v + 2])};
        }
        c.indices.resize(size_t(info.triangleCount) * 3);
        if (loc.flags & kIndices16) {
            std::vector<uint16_t> small(c.indices.size());
            r.getArray(small.data(), small.size(), "indices");
            std::copy(small.begin(), small.end(), c.indices.begin());
        } else {
            r.getArray(c.indices.data(), c.indices.size(), "indices");
        }
        for (size_t i = 0; i < c.indices.size(); ++i)
            if (c.indices[i] >= info.vertexCount)
                fail("triangle " + std::to_string(i / 3) + " uses vertex " + std::to_string(c.indices[i]) +
                     " of " + std::to_string(info.vertexCount));
        return c;
    }

private:
    void readHeaders() {
        std::array<char, kFileHeaderBytes> head{};
        if (fileBytes_ < kFileHeaderBytes)
            throw scene::InputError(name_ + ": truncated: " + std::to_string(fileBytes_) +
                                    " bytes, shorter than the 32-byte geometry stream header");
        file_.readAt(0, head.data(), head.size(), name_);
        ByteReader h(std::string_view(head.data(), head.size()), name_);
        std::array<char, 4> magic = h.get<std::array<char, 4>>("magic");
        if (std::memcmp(magic.data(), kFileMagic, 4) != 0) h.fail("magic", "not a geometry stream (no CGS1 magic)");
        const uint32_t version = h.get<uint32_t>("version");
        if (version != kVersion) h.fail("version", "unsupported version " + std::to_string(version));
        const uint64_t chunks = h.get<uint64_t>("chunk count");
        const uint64_t triangles = h.get<uint64_t>("triangle count");
        // Each chunk takes at least its header: a count the file cannot hold is rejected before
        // anything is allocated for it.
        if (chunks > (fileBytes_ - kFileHeaderBytes) / kChunkHeaderBytes)
            h.fail("chunk count", std::to_string(chunks) + " chunks cannot fit in " + std::to_string(fileBytes_) +
                                      " bytes (truncated?)");
        uint64_t at = kFileHeaderBytes, triangleSum = 0;
        for (uint64_t i = 0; i < chunks; ++i) {
            const std::string where = name_ + ": chunk " + std::to_string(i);
            std::array<char, kChunkHeaderBytes> ch{};
            if (fileBytes_ - at < kChunkHeaderBytes)
                throw scene::InputError(where + " at byte " + std::to_string(at) + ": truncated: the file ends inside the chunk header");
            file_.readAt(at, ch.data(), ch.size(), where);
            ByteReader r(std::string_view(ch.data(), ch.size()), where, at);
            magic = r.get<std::array<char, 4>>("chunk magic");
            if (std::memcmp(magic.data(), kChunkMagic, 4) != 0) r.fail("chunk magic", "no CHNK magic (corrupt)");
            ChunkLocation loc;
            ChunkInfo info;
            loc.flags = r.get<uint32_t>("flags");
            info.vertexCount = r.get<uint32_t>("vertex count");
            info.triangleCount = r.get<uint32_t>("triangle count");
            info.hasColors = loc.flags & kHasColors;
            info.boundsMin = r.get<glm::vec3>("bounds");
            info.boundsMax = r.get<glm::vec3>("bounds");
            loc.rawBytes = r.get<uint32_t>("raw bytes");
            loc.compressedBytes = r.get<uint32_t>("compressed bytes");
            if ((loc.flags & ~uint32_t(kHasColors | kIndices16)) != 0) r.fail("flags", "unknown flags");
            if ((loc.flags & kIndices16) && info.vertexCount > 65536)
                r.fail("flags", "16-bit indices with more than 65536 vertices");
            if (loc.rawBytes != rawPayloadBytes(info.vertexCount, info.triangleCount, loc.flags))
                r.fail("raw bytes", "does not match the vertex and triangle counts (corrupt)");
            loc.payloadOffset = at + kChunkHeaderBytes;
            // LZ4 expands a byte to at most 255 (a run of one value): a larger raw size is corrupt,
            // and refusing it here keeps a forged header from asking for gigabytes.
            if (uint64_t(loc.rawBytes) > uint64_t(loc.compressedBytes) * 255 + 64)
                r.fail("raw bytes", "more than " + std::to_string(loc.compressedBytes) +
                                        " LZ4-compressed bytes can hold (corrupt)");
            if (loc.compressedBytes > fileBytes_ - loc.payloadOffset)
                r.fail("compressed bytes", "truncated: the chunk needs " + std::to_string(loc.compressedBytes) +
                                               " bytes, " + std::to_string(fileBytes_ - loc.payloadOffset) + " remain");
            at = loc.payloadOffset + loc.compressedBytes;
            triangleSum += info.triangleCount;
            locations_.push_back(loc);
            infos_.push_back(info);
        }
        if (triangleSum != triangles)
            throw scene::InputError(name_ + ": the header's triangle count " + std::to_string(triangles) +
                                    " does not match the chunks' " + std::to_string(triangleSum) + " (corrupt)");
        if (at != fileBytes_)
            throw scene::InputError(name_ + " at byte " + std::to_string(at) + ": " +
                                    std::to_string(fileBytes_ - at) + " bytes after the last chunk (corrupt)");
    }

    std::string name_;
    PositionalFile file_;
    uint64_t fileBytes_;
    std::vector<ChunkLocation> locations_;
    std::vector<ChunkInfo> infos_;
};

}  // namespace

GeometryStreamWriteStats writeGeometryStream(const MeshView& view, std::ostream& out) {
    GeometryStreamWriteStats stats;
    stats.chunks = view.chunkCount();
    stats.triangles = view.triangleCount();
    ByteWriter head;
    head.putArray(kFileMagic, 4);
    head.put(kVersion);
    head.put(uint64_t(stats.chunks));
    head.put(uint64_t(stats.triangles));
    head.put(uint64_t(0));
    out.write(head.bytes().data(), std::streamsize(head.size()));
    for (size_t i = 0; i < view.chunkCount(); ++i) {
        const GeometryChunk c = view.readChunk(i);
        const ChunkInfo& info = view.chunkInfo(i);
        uint32_t flags = 0;
        if (c.hasColors()) flags |= kHasColors;
        if (c.positions.size() <= 65536) flags |= kIndices16;
        const std::string raw = serializePayload(c, flags);
        const std::vector<char> packed = compressFrame(raw);
        ByteWriter h;
        h.putArray(kChunkMagic, 4);
        h.put(flags);
        h.put(uint32_t(c.positions.size()));
        h.put(uint32_t(c.triangleCount()));
        h.put(info.boundsMin);
        h.put(info.boundsMax);
        h.put(uint32_t(raw.size()));
        h.put(uint32_t(packed.size()));
        h.padTo(kChunkHeaderBytes);
        out.write(h.bytes().data(), std::streamsize(h.size()));
        out.write(packed.data(), std::streamsize(packed.size()));
        stats.vertices += c.positions.size();
        stats.rawBytes += raw.size();
        stats.compressedBytes += packed.size();
    }
    if (!out) throw std::runtime_error("writing the geometry stream failed");
    return stats;
}

std::unique_ptr<MeshView> openGeometryStream(const std::filesystem::path& path) {
    return std::make_unique<GeometryStreamView>(path);
}

}  // namespace cuberille::voxel
