#pragma once
// What the camera sees at each pixel centre, for the shadow stage: a visibility buffer (Burns
// and Hunt, 2013). The casters are drawn once through the software GPU with one sample per pixel
// at its centre (the position the shade stage evaluates), each triangle writing its own id as a
// flat colour; then each pixel's position is the camera ray through its centre met with that
// triangle's plane, and its normal the triangle's, turned toward the camera. Drawn with the
// scene's own order, culling and depth test, so the surface found is the one the frame shades.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// A run of caster triangles drawn as one draw call (one mesh of the scene), with its culling.
struct CasterRange {
    uint32_t firstTriangle = 0, triangleCount = 0;
    uint32_t firstVertex = 0, vertexCount = 0;  // the vertices its triangles use
    raster::CullMode cull = raster::CullMode::None;
};

struct ScreenSurfaces {
    int width = 0, height = 0;
    std::vector<uint32_t> triangle;  // per pixel; kNone where no caster is seen
    std::vector<glm::vec3> position, normal;  // world space; normal unit, facing the camera

    static constexpr uint32_t kNone = ~0u;
    bool covered(size_t pixel) const { return triangle[pixel] != kNone; }
};

ScreenSurfaces findScreenSurfaces(const TriangleMeshView& casters, std::span<const CasterRange> ranges,
                                  const glm::mat4& clipFromWorld, int width, int height);

}  // namespace cuberille::rt
