#pragma once
// Axis-aligned bounding boxes, the bounding volume of every hierarchy in rt/. An empty box has
// lo > hi on every axis, so growing it by anything gives that thing's box and merging it changes
// nothing; all operations are exact (min and max), which is what makes refits deterministic.

#include <algorithm>
#include <limits>

#include <glm/glm.hpp>

namespace cuberille::rt {

struct Aabb {
    glm::vec3 lo{std::numeric_limits<float>::max()};
    glm::vec3 hi{std::numeric_limits<float>::lowest()};

    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }

    void grow(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void grow(const Aabb& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    glm::vec3 extent() const { return hi - lo; }
    glm::vec3 centre() const { return (lo + hi) * 0.5f; }

    /// The surface area: proportional to the chance that a random ray hits the box (the surface
    /// area heuristic), and the quantity Lauterbach's rebuild criterion compares.
    float surfaceArea() const {
        if (empty()) return 0.0f;
        const glm::vec3 e = extent();
        return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
    }

    bool contains(const Aabb& b) const {
        return b.lo.x >= lo.x && b.lo.y >= lo.y && b.lo.z >= lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y &&
               b.hi.z <= hi.z;
    }
    bool operator==(const Aabb&) const = default;
};

inline Aabb merged(Aabb a, const Aabb& b) {
    a.grow(b);
    return a;
}

}  // namespace cuberille::rt
