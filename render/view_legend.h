#pragma once
// Legends for the views that colour the pipeline's decisions (--view tiles, overdraw, lod,
// visibility): a box in the image's lower-left corner with a swatch and a label per colour, drawn
// with the built-in bitmap font (render/bitmap_font.h). `--no-legend` leaves it out.

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raster/resolve.h"
#include "render/frame_settings.h"

namespace cuberille::render {

struct LegendEntry {
    glm::vec3 color;  // linear
    std::string label;
};

/// The entries of a view: its colours and what they mean. `drawnPerLevel`: the lod view's blocks
/// drawn by level (only levels that drew something are listed); `debugCamera` adds the
/// visibility view's frustum-culled grey. Empty for views without a legend.
std::vector<LegendEntry> legendFor(View view, const std::vector<uint64_t>& drawnPerLevel, bool debugCamera);

/// Draws the entries into the image's lower-left corner, scaled with the image's height (font
/// pixels of 1 image pixel up to 400 rows, 2 up to 800, ...). Nothing when they do not fit.
void drawLegend(raster::Image& image, const std::vector<LegendEntry>& entries);

}  // namespace cuberille::render
