#pragma once
// The voxel model file (.cvox): a header, a block table, then each block's data. Blocks are
// independently addressable (byte ranges in the table), so a renderer can stream them in any
// order (lod/); the table also carries each block's level and tight voxel bounds, which culling
// reads without touching voxel data.
//
// Layout (little-endian; docs/formats.md has the table):
//   header, 96 bytes: "CVOX", version, resolution, block size, level count, separability,
//                     flags (1: colours from the source, 2: source triangles), origin (3 double),
//                     extent (double), block count, voxel count, triangle count, reserved
//   block table, 64 bytes per block: level, coord (3 uint32), voxel count, triangle count,
//                     voxel byte offset, triangle byte offset, tight min and max (3+3 uint8), reserved
//   block data: packed voxels, normals, colours (uint32 each), then source triangles
//               (3 positions float32 x3, 3 normals, 3 colours: 60 bytes each)

#include <filesystem>
#include <memory>
#include <ostream>

#include "voxel/voxel_model.h"

namespace cuberille::voxel {

class PositionalFile;

/// Throws std::runtime_error when the stream fails.
void writeCvox(const VoxelModel& model, std::ostream& out);

/// writeCvox in two steps, for a model written a block at a time (lod/pyramid_ranges.h): the header
/// and block table from a layout (each block's counts as totalVoxels()/totalTriangles() give them;
/// no voxel data needed), then each block's data in table order, either from a loaded block or
/// as the bytes blockData gives (voxels, normals, colours, then source triangles).
void writeCvoxHeaderAndTable(const VoxelModel& layout, std::ostream& out);
void writeCvoxBlockData(const VoxelBlock& block, std::ostream& out);
/// Bytes of a block's data in the file: 12 per voxel, 60 per source triangle.
uint64_t cvoxBlockDataBytes(uint64_t voxels, uint64_t triangles);

/// A .cvox opened for reading blocks on demand: the header and block table are read and checked
/// when it opens (a truncated or corrupted file throws scene::InputError naming the file, the
/// block or field, and the byte offset); a block's voxels and triangles are read when asked for,
/// from any thread (positional reads).
class CvoxReader {
public:
    explicit CvoxReader(const std::filesystem::path& path);
    ~CvoxReader();
    CvoxReader(const CvoxReader&) = delete;
    CvoxReader& operator=(const CvoxReader&) = delete;

    /// The model with every block's metadata (level, coordinates, tight bounds, links) and no
    /// voxel or triangle data.
    const VoxelModel& layout() const { return layout_; }
    size_t blockCount() const { return layout_.blocks.size(); }
    /// The parts of a block to read: streaming reads a block's voxels and its source triangles
    /// when each is needed (lod/streaming_blocks.h).
    enum Parts : uint8_t { kVoxels = 1, kTriangles = 2, kAllParts = 3 };
    VoxelBlock load(size_t block, Parts parts = kAllParts) const;
    /// Bytes a block's parts take in the file (voxels: 12 per voxel; triangles: 60 each).
    uint64_t partBytes(size_t block, Parts parts) const;

private:
    struct BlockData {
        uint32_t voxels = 0, triangles = 0;
        uint64_t voxelOffset = 0, triangleOffset = 0;
    };
    std::string name_;
    std::unique_ptr<PositionalFile> file_;
    uint64_t fileBytes_ = 0;
    VoxelModel layout_;
    std::vector<BlockData> offsets_;
};

/// Reads a whole .cvox file (through CvoxReader).
VoxelModel readCvox(const std::filesystem::path& path);

}  // namespace cuberille::voxel
