#pragma once
// The geometry every hierarchy in rt/ is built over: indexed triangles, borrowed. A deforming
// mesh keeps its indices and moves its positions between frames, which is exactly what a refit
// (rather than a rebuild) can follow.

#include <cstddef>
#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "rt/aabb.h"

namespace cuberille::rt {

struct TriangleMeshView {
    std::span<const glm::vec3> positions;
    std::span<const uint32_t> indices;  // three per triangle

    size_t triangleCount() const { return indices.size() / 3; }

    glm::vec3 vertex(size_t triangle, int corner) const { return positions[indices[3 * triangle + corner]]; }

    Aabb triangleBounds(size_t triangle) const {
        Aabb b;
        for (int c = 0; c < 3; ++c) b.grow(vertex(triangle, c));
        return b;
    }
};

}  // namespace cuberille::rt
