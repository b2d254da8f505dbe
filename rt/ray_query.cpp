#include "rt/ray_query.h"

namespace cuberille::rt {
namespace {

struct NodeBoxes {
    const Bvh& bvh;
    Aabb operator()(uint32_t node) const { return bvh.nodes[node].box(); }
};

struct LeafVertices {
    const Bvh& bvh;
    const glm::vec3& operator()(uint32_t slot, int corner) const { return bvh.leafVertices[3 * size_t(slot) + corner]; }
};

}  // namespace

RayHit closestHit(const Bvh& bvh, const TriangleMeshView&, const Ray& ray) {
    return detail::traverse<false>(bvh, ray, NodeBoxes{bvh}, LeafVertices{bvh});
}

RayHit closestHit(const Bvh& bvh, const TriangleMeshView&, const Ray& ray, TraversalCounters& counters) {
    return detail::traverse<false>(bvh, ray, NodeBoxes{bvh}, LeafVertices{bvh}, &counters);
}

RayHit closestHit(const Bvh& bvh, const TriangleMeshView&, const Ray& ray, const HitFilter& filter) {
    return detail::traverse<false>(bvh, ray, NodeBoxes{bvh}, LeafVertices{bvh}, nullptr, &filter);
}

bool anyHit(const Bvh& bvh, const TriangleMeshView&, const Ray& ray, const HitFilter* filter) {
    return detail::traverse<true>(bvh, ray, NodeBoxes{bvh}, LeafVertices{bvh}, nullptr, filter).hit();
}

RayHit closestHitBruteForce(const TriangleMeshView& mesh, const Ray& ray, const HitFilter* filter) {
    const WatertightRay test(ray);
    RayHit best;
    best.t = ray.tMax;
    for (uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        offerHit(test, mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), t, ray.tMin, best, filter, &ray);
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
}

bool anyHitBruteForce(const TriangleMeshView& mesh, const Ray& ray, const HitFilter* filter) {
    const WatertightRay test(ray);
    for (uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        RayHit best;
        best.t = ray.tMax;
        if (offerHit(test, mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), t, ray.tMin, best, filter, &ray)) return true;
    }
    return false;
}

}  // namespace cuberille::rt
