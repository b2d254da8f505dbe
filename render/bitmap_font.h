#pragma once
// A 5x7 bitmap font for labels drawn into images (the legends of the diagnostic views,
// render/view_legend.h): upper-case letters, digits and - + / . , ( ) : and space; lower case is
// drawn as upper case, anything else as a blank. Drawn without any font library, so a legend
// costs nothing at start-up (OpenImageIO is loaded only for what needs it).

#include <string>

#include <glm/glm.hpp>

#include "raster/resolve.h"

namespace cuberille::render {

inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;  // in font pixels

/// Draws `text` with its top-left corner at (x, y), each font pixel `scale` image pixels square,
/// in the linear colour given; pixels outside the image are skipped.
void drawText(raster::Image& image, int x, int y, const std::string& text, int scale, const glm::vec3& color);

/// The width `text` takes in image pixels.
inline int textWidth(const std::string& text, int scale) { return int(text.size()) * kGlyphAdvance * scale; }

}  // namespace cuberille::render
