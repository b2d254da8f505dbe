#pragma once
// Frustum culling of a 3D scene's meshes through one BVH over all their triangles
// (rt/frustum_cull.h), node by node: subtrees outside a plane are dropped whole, subtrees inside
// all six taken whole. For animated glTF (`render --animate`), the same hierarchy follows the
// poses: refitted every frame, rebuilt when Lauterbach's criterion says so (rt/deforming_bvh.h).
//
// Culling keeps each mesh's surviving triangles in their order, and drops only triangles whose
// boxes lie outside the frustum (which the clipper would reject anyway), so the image is the
// same with and without it; only the work differs.

#include <optional>
#include <vector>

#include "rt/deforming_bvh.h"
#include "rt/frustum_cull.h"
#include "scene/scene.h"

namespace cuberille::render {

struct FrustumCullStats {
    uint64_t trianglesIn = 0, trianglesKept = 0;
    rt::FrustumCullCounters counters;
    double buildMs = 0.0;   // the hierarchy's build (first frame) or update (later frames)
    double cullMs = 0.0;
    double degradation = 0.0;
    bool rebuilt = false;
};

class SceneFrustumCull {
public:
    /// `method`: how update() follows each new pose (rt/deforming_bvh.h). The cull reads every box
    /// it reaches, so a lazy tree is brought up to date first: lazy saves the cull nothing.
    explicit SceneFrustumCull(const scene::Scene& scene, rt::BvhUpdateMethod method = rt::BvhUpdateMethod::Refit);

    /// A new pose of the same scene (same meshes, same triangles, moved vertices): refit.
    void update(const scene::Scene& scene);

    /// Replaces every mesh's indices with those of its triangles not outside the camera's frustum.
    FrustumCullStats cull(scene::Scene& scene, float aspect);

private:
    void gather(const scene::Scene& scene);

    std::vector<glm::vec3> positions_;
    std::vector<uint32_t> indices_;           // all triangles, vertex indices into positions_
    std::vector<uint32_t> firstTriangle_;     // per mesh, and one past the last
    std::vector<uint32_t> firstVertex_;       // per mesh
    std::optional<rt::DeformingBvh> bvh_;
    FrustumCullStats pending_;                // the build or update, reported with the next cull
};

}  // namespace cuberille::render
