#pragma once
// Triangle-list scenes (`.tri`, DESIGN.md): UTF-8 text, `#` starts a comment, one triangle per
// line `x0 y0 x1 y1 x2 y2 v` or `x0 y0 x1 y1 x2 y2 r g b`, in window pixels. Drawn in file
// order, no depth test, no culling, on a background of 0.
//
// Numbers are read as 32-bit floats (the vertex format), which set-up then snaps to 1/256
// pixel; anything that is not a finite number, and any other count of numbers, is an error
// naming the file and line.

#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"

namespace cuberille::scene {

struct TriScene {
    std::vector<glm::vec3> positions;  // window space, three per triangle, z = 0
    std::vector<glm::vec4> colors;     // per triangle, linear RGBA (alpha 1)

    size_t triangleCount() const { return colors.size(); }
    /// The draw DESIGN.md prescribes: window space, no depth test, no culling.
    raster::DrawCall drawCall() const;
};

/// Throws InputError("FILE:LINE: problem") on malformed input.
TriScene parseTriScene(const std::string& text, const std::string& fileName);
TriScene loadTriScene(const std::filesystem::path& path);

}  // namespace cuberille::scene
