#pragma once
// The multisampled render target: per-sample linear RGBA colour and float depth, stored tile by
// tile (64x64 pixels, pixel-major inside a tile, samples of a pixel adjacent), so one back-end
// task touches one contiguous piece of memory.
//
// Clearing is lazy: a tile is cleared by the back-end task that first draws into it, and a
// tile nothing drew into resolves straight to the clear values (a frame that covers a small
// part of the screen pays for that part only).
//
// Debug buffers (overdraw counts, coarse classes per block) exist only when a view asks.

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "raster/limits.h"

namespace cuberille::raster {

/// How window depth maps to distance. Standard: 0 at the near plane, 1 at the far plane. Reversed:
/// 1 at the near plane, 0 at the far plane, so distant surfaces get float's dense values near 0
/// instead of its sparse ones near 1 (the projection must be built for it: scene::Camera's
/// reversedDepth). Either way the rasterizer stores and compares a depth *key* with LESS: the
/// depth itself (standard) or its negation (reversed), an exact sign flip, so the depth test,
/// hierarchical Z and every bound keep one direction (raster/depth.h).
enum class DepthConvention : uint8_t { Standard, Reversed };

/// glm::perspectiveRH_ZO in a depth convention. Reversed: z_clip = n/(f-n) z_view + f n/(f-n)
/// and w = -z_view, so at view distance d the depth is n (f - d) / ((f - n) d), 1 at the near
/// plane and 0 at the far one, falling like 1/d; built directly rather than as 1 - z, whose
/// cancellation near 1 would throw away the precision reversed depth exists for.
glm::mat4 perspectiveProjection(float fovyRadians, float aspect, float nearPlane, float farPlane, DepthConvention convention);

struct FramebufferDesc {
    int widthPixels = 0;
    int heightPixels = 0;
    int samples = 1;
    glm::vec4 clearColor{0.0f};
    float clearDepth = 1.0f;  // how far a cleared sample is, 1 = the far plane (either convention)
    DepthConvention depthConvention = DepthConvention::Standard;
    bool recordOverdraw = false;     // depth-passing samples per pixel
    bool recordBlockClasses = false; // coarse classifications per 8x8 block
    bool hierarchicalDepth = true;   // reject hidden 8x8 blocks before per-sample depth tests
    /// False: a depth-only target (shadow maps), with no colour storage to allocate, clear or
    /// resolve; it takes only draws whose colour write mask is 0.
    bool colorAttachment = true;
};

/// The stored key of a window depth, and back (exact: a sign flip).
inline float depthKeySign(DepthConvention c) { return c == DepthConvention::Reversed ? -1.0f : 1.0f; }
/// The key a cleared sample holds: 1 - clearDepth as a reversed depth, negated.
inline float clearDepthKey(const FramebufferDesc& d) {
    return d.depthConvention == DepthConvention::Reversed ? d.clearDepth - 1.0f : d.clearDepth;
}

class Framebuffer {
public:
    void reset(const FramebufferDesc& desc);

    /// The bytes reset(desc) allocates: per sample a 4-byte depth key and, with a colour
    /// attachment, 16 bytes of linear RGBA, over whole 64x64 tiles; per 8x8 block a 4-byte
    /// hierarchical-Z bound; the overdraw and block-class records when asked for.
    static uint64_t bytesFor(const FramebufferDesc& desc);

    const FramebufferDesc& desc() const { return desc_; }
    int width() const { return desc_.widthPixels; }
    int height() const { return desc_.heightPixels; }
    int samples() const { return desc_.samples; }
    int tilesX() const { return tilesX_; }
    int tilesY() const { return tilesY_; }
    int tileCount() const { return tilesX_ * tilesY_; }

    /// Sample storage of one tile, index (pixelY * 64 + pixelX) * samples + sample. A depth-only
    /// target has no colour: tileColor is null.
    glm::vec4* tileColor(int tile) { return hasColor() ? color_.get() + size_t(tile) * samplesPerTile() : nullptr; }
    float* tileDepth(int tile) { return depth_.get() + size_t(tile) * samplesPerTile(); }
    const glm::vec4* tileColor(int tile) const {
        return hasColor() ? color_.get() + size_t(tile) * samplesPerTile() : nullptr;
    }
    bool hasColor() const { return desc_.colorAttachment; }
    const float* tileDepth(int tile) const { return depth_.get() + size_t(tile) * samplesPerTile(); }

    /// Hierarchical Z: per 8x8 block of the tile (row-major, 64 entries), an upper bound on
    /// every stored sample depth in the block. Never below the true maximum, so a triangle whose
    /// depth over a block is not less than it cannot pass a LESS test anywhere in the block.
    float* tileBlockMaxDepth(int tile) { return blockMaxDepth_.get() + size_t(tile) * kBlocksPerTile; }
    const float* tileBlockMaxDepth(int tile) const { return blockMaxDepth_.get() + size_t(tile) * kBlocksPerTile; }

    /// Sets each 8x8 block's hierarchical Z in a touched tile to the largest key its samples
    /// inside the image hold: the tightest bound there is. The back end lowers a block's bound
    /// only when one triangle replaced every sample of it, so after many small triangles (a scan,
    /// sub-pixel voxel faces) the bound stays at the clear depth; the exact maximum lets later
    /// draws' hidden blocks be rejected, and can be read to cull geometry before it is drawn
    /// (farthestDepthKeyOfBlock). Samples outside the image are never tested, so they are left out
    /// of the maximum. Touches nothing else: the image does not change.
    void tightenHierarchicalDepth(int tile);
    /// The hierarchical-Z bound of block (blockX, blockY) of the image: no sample of the block
    /// holds a key above it. A block of a tile nothing drew into holds the clear key.
    float farthestDepthKeyOfBlock(int blockX, int blockY) const;

    bool tileTouched(int tile) const { return tileTouched_[tile] != 0; }
    /// Clears the tile's samples on first use; called by the one task that owns the tile.
    void touchTile(int tile);

    // Debug buffers, linear over the image (overdraw) and over 8x8 blocks (classes).
    uint32_t* overdraw() { return overdraw_.empty() ? nullptr : overdraw_.data(); }
    const std::vector<uint32_t>& overdrawCounts() const { return overdraw_; }
    uint32_t* blockPartialCounts() { return blockPartial_.empty() ? nullptr : blockPartial_.data(); }
    uint32_t* blockFullCounts() { return blockFull_.empty() ? nullptr : blockFull_.data(); }
    const std::vector<uint32_t>& blockPartial() const { return blockPartial_; }
    const std::vector<uint32_t>& blockFull() const { return blockFull_; }
    int blocksX() const { return (desc_.widthPixels + kBlockSizePixels - 1) / kBlockSizePixels; }
    int blocksY() const { return (desc_.heightPixels + kBlockSizePixels - 1) / kBlockSizePixels; }

    size_t samplesPerTile() const { return size_t(kPixelsPerTile) * desc_.samples; }

private:
    FramebufferDesc desc_;
    int tilesX_ = 0, tilesY_ = 0;
    // Not value-initialised: every tile is cleared by touchTile() before it is read.
    std::unique_ptr<glm::vec4[]> color_;
    std::unique_ptr<float[]> depth_;
    size_t sampleCapacity_ = 0, colorCapacity_ = 0;
    std::unique_ptr<float[]> blockMaxDepth_;
    size_t blockCapacity_ = 0;
    std::vector<uint8_t> tileTouched_;
    std::vector<uint32_t> overdraw_, blockPartial_, blockFull_;
};

}  // namespace cuberille::raster
