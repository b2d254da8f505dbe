#include "raster/framebuffer.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/huge_pages.h"

namespace cuberille::raster {

glm::mat4 perspectiveProjection(float fovyRadians, float aspect, float nearPlane, float farPlane, DepthConvention convention) {
    glm::mat4 m = glm::perspectiveRH_ZO(fovyRadians, aspect, nearPlane, farPlane);
    if (convention == DepthConvention::Reversed) {
        const double n = nearPlane, f = farPlane;
        m[2][2] = float(n / (f - n));
        m[3][2] = float(f * n / (f - n));
    }
    return m;
}

void Framebuffer::reset(const FramebufferDesc& desc) {
    if (desc.widthPixels <= 0 || desc.heightPixels <= 0 ||
        desc.widthPixels > kMaxFramebufferPixels || desc.heightPixels > kMaxFramebufferPixels)
        throw std::invalid_argument("framebuffer size must be 1.." +
                                    std::to_string(kMaxFramebufferPixels) + " pixels per side");
    desc_ = desc;
    tilesX_ = (desc.widthPixels + kTileSizePixels - 1) / kTileSizePixels;
    tilesY_ = (desc.heightPixels + kTileSizePixels - 1) / kTileSizePixels;
    // Storage is kept across frames that fit in it: no per-frame allocation or fill.
    const size_t samples = size_t(tileCount()) * samplesPerTile();
    if (samples > sampleCapacity_) {
        depth_ = std::make_unique_for_overwrite<float[]>(samples);
        adviseHugePages(depth_.get(), samples * sizeof(float));
        sampleCapacity_ = samples;
    }
    if (desc.colorAttachment && samples > colorCapacity_) {
        color_ = std::make_unique_for_overwrite<glm::vec4[]>(samples);
        adviseHugePages(color_.get(), samples * sizeof(glm::vec4));
        colorCapacity_ = samples;
    }
    if (size_t(tileCount()) * kBlocksPerTile > blockCapacity_) {
        blockCapacity_ = size_t(tileCount()) * kBlocksPerTile;
        blockMaxDepth_ = std::make_unique_for_overwrite<float[]>(blockCapacity_);
    }
    tileTouched_.assign(tileCount(), 0);
    const size_t pixels = size_t(desc.widthPixels) * desc.heightPixels;
    const size_t blocks = size_t(blocksX()) * blocksY();
    if (desc.recordOverdraw) overdraw_.assign(pixels, 0); else overdraw_.clear();
    if (desc.recordBlockClasses) {
        blockPartial_.assign(blocks, 0);
        blockFull_.assign(blocks, 0);
    } else {
        blockPartial_.clear();
        blockFull_.clear();
    }
}

uint64_t Framebuffer::bytesFor(const FramebufferDesc& d) {
    const uint64_t tiles = uint64_t((d.widthPixels + kTileSizePixels - 1) / kTileSizePixels) *
                           uint64_t((d.heightPixels + kTileSizePixels - 1) / kTileSizePixels);
    const uint64_t samples = tiles * kPixelsPerTile * uint64_t(d.samples);
    const uint64_t pixels = uint64_t(d.widthPixels) * uint64_t(d.heightPixels);
    uint64_t bytes = samples * (sizeof(float) + (d.colorAttachment ? sizeof(glm::vec4) : 0)) +
                     tiles * kBlocksPerTile * sizeof(float) + tiles;
    if (d.recordOverdraw) bytes += pixels * sizeof(uint32_t);
    if (d.recordBlockClasses) bytes += 2 * tiles * kBlocksPerTile * sizeof(uint32_t);
    return bytes;
}

void Framebuffer::touchTile(int tile) {
    if (tileTouched_[tile]) return;
    tileTouched_[tile] = 1;
    if (hasColor()) std::fill_n(tileColor(tile), samplesPerTile(), desc_.clearColor);
    std::fill_n(tileDepth(tile), samplesPerTile(), clearDepthKey(desc_));
    std::fill_n(tileBlockMaxDepth(tile), kBlocksPerTile, clearDepthKey(desc_));
}

void Framebuffer::tightenHierarchicalDepth(int tile) {
    if (!tileTouched_[tile]) return;
    const int originX = (tile % tilesX_) * kTileSizePixels, originY = (tile / tilesX_) * kTileSizePixels;
    const int width = std::min(kTileSizePixels, desc_.widthPixels - originX);
    const int height = std::min(kTileSizePixels, desc_.heightPixels - originY);
    const int samples = desc_.samples;
    const float* depth = tileDepth(tile);
    float* bound = tileBlockMaxDepth(tile);
    for (int by = 0; by * kBlockSizePixels < height; ++by)
        for (int bx = 0; bx * kBlockSizePixels < width; ++bx) {
            const int x0 = bx * kBlockSizePixels, x1 = std::min(x0 + kBlockSizePixels, width);
            const int y1 = std::min((by + 1) * kBlockSizePixels, height);
            float farthest = -std::numeric_limits<float>::infinity();
            for (int y = by * kBlockSizePixels; y < y1; ++y) {
                const float* row = depth + (size_t(y) * kTileSizePixels + size_t(x0)) * size_t(samples);
                for (int i = 0; i < (x1 - x0) * samples; ++i) farthest = std::max(farthest, row[i]);
            }
            bound[by * kBlocksPerTileSide + bx] = farthest;
        }
}

float Framebuffer::farthestDepthKeyOfBlock(int blockX, int blockY) const {
    const int tile = (blockY / kBlocksPerTileSide) * tilesX_ + blockX / kBlocksPerTileSide;
    if (!tileTouched_[tile]) return clearDepthKey(desc_);
    return tileBlockMaxDepth(tile)[(blockY % kBlocksPerTileSide) * kBlocksPerTileSide + blockX % kBlocksPerTileSide];
}

}  // namespace cuberille::raster
