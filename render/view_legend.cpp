#include "render/view_legend.h"

#include <algorithm>

#include "lod/voxel_scene.h"
#include "render/bitmap_font.h"

namespace cuberille::render {
namespace {

// The legend box over the image: its background dimmed to a quarter, so labels read on any view.
constexpr float kBoxDimming = 0.25f;

}  // namespace

std::vector<LegendEntry> legendFor(View view, const std::vector<uint64_t>& drawnPerLevel, bool debugCamera) {
    switch (view) {
        case View::Tiles:
            return {{raster::kBlockFullColor, "8x8 block fully covered"},
                    {raster::kBlockPartialColor, "partly covered"},
                    {raster::kBlockBothColor, "both (by different triangles)"},
                    {raster::kBlockUntouchedColor, "untouched"},
                    {glm::vec3(1.0f), "64x64 tile edges"}};
        case View::Overdraw:
            return {{raster::overdrawColor(1.0f), "1 layer of depth-passing samples"},
                    {raster::overdrawColor(2.0f), "2 layers"},
                    {raster::overdrawColor(4.0f), "4 layers"},
                    {raster::overdrawColor(8.0f), "8 or more layers"},
                    {glm::vec3(0.0f), "none"}};
        case View::Lod: {
            std::vector<LegendEntry> entries;
            for (size_t level = 0; level < drawnPerLevel.size(); ++level)
                if (drawnPerLevel[level] > 0)
                    entries.push_back({lod::levelColor(uint32_t(level)), "level " + std::to_string(level) +
                                                                         (level == 0 ? " (finest)" : "")});
            entries.push_back({lod::lodSourceTrianglesColor(), "source triangles"});
            return entries;
        }
        case View::Visibility: {
            std::vector<LegendEntry> entries = {{lod::kVisibleBlockColor, "drawn as voxels"},
                                                {lod::kSourceTrianglesColor, "drawn from source triangles"},
                                                {lod::kOcclusionCulledColor, "occlusion-culled (tested)"}};
            if (debugCamera) entries.push_back({lod::kOutsideFrustumColor, "outside the frustum"});
            return entries;
        }
        default: return {};
    }
}

void drawLegend(raster::Image& image, const std::vector<LegendEntry>& entries) {
    if (entries.empty()) return;
    const int scale = 1 + image.height / 400, pad = 3 * scale, row = (kGlyphHeight + 3) * scale;
    const int swatch = kGlyphHeight * scale;
    size_t longest = 0;
    for (const LegendEntry& e : entries) longest = std::max(longest, e.label.size());
    const int boxWidth = pad + swatch + 2 * scale + textWidth(std::string(longest, 'x'), scale) + pad;
    const int boxHeight = pad + int(entries.size()) * row - 3 * scale + pad;
    if (boxWidth > image.width || boxHeight > image.height) return;
    const int left = 0, top = image.height - boxHeight;
    for (int y = top; y < image.height; ++y)
        for (int x = left; x < left + boxWidth; ++x) {
            float* p = image.pixel(x, y);
            for (int c = 0; c < 3; ++c) p[c] *= kBoxDimming;
            p[3] = 1.0f;  // the legend is opaque even over a transparent background
        }
    for (size_t i = 0; i < entries.size(); ++i) {
        const int y = top + pad + int(i) * row;
        for (int dy = 0; dy < swatch; ++dy)
            for (int dx = 0; dx < swatch; ++dx) {
                float* p = image.pixel(left + pad + dx, y + dy);
                p[0] = entries[i].color.r, p[1] = entries[i].color.g, p[2] = entries[i].color.b;
            }
        drawText(image, left + pad + swatch + 2 * scale, y, entries[i].label, scale, glm::vec3(0.9f));
    }
}

}  // namespace cuberille::render
