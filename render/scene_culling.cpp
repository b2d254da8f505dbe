#include "render/scene_culling.h"

#include <stdexcept>

#include "raster/clock.h"

namespace cuberille::render {

void SceneFrustumCull::gather(const scene::Scene& s) {
    positions_.clear();
    indices_.clear();
    firstTriangle_.assign(1, 0);
    firstVertex_.clear();
    for (const scene::Mesh& m : s.meshes) {
        const uint32_t base = uint32_t(positions_.size());
        firstVertex_.push_back(base);
        positions_.insert(positions_.end(), m.positions.begin(), m.positions.end());
        for (const uint32_t i : m.indices) indices_.push_back(base + i);
        firstTriangle_.push_back(uint32_t(indices_.size() / 3));
    }
}

SceneFrustumCull::SceneFrustumCull(const scene::Scene& s, rt::BvhUpdateMethod method) {
    const double t0 = raster::nowMs();
    gather(s);
    // The cull walks the binary tree and traces no rays: no wide copy.
    bvh_.emplace(rt::TriangleMeshView{positions_, indices_}, method, rt::BvhBuildOptions{}, 0.4, rt::RayQueryTree::Binary);
    pending_.buildMs = raster::nowMs() - t0;
    pending_.rebuilt = true;
}

void SceneFrustumCull::update(const scene::Scene& s) {
    const double t0 = raster::nowMs();
    const size_t triangles = indices_.size() / 3;
    gather(s);
    if (indices_.size() / 3 != triangles) throw std::runtime_error("the animated scene changed its triangle count");
    const rt::BvhUpdateReport report = bvh_->update({positions_, indices_});
    pending_.buildMs = raster::nowMs() - t0;
    pending_.degradation = report.degradation;
    pending_.rebuilt = report.rebuilt;
}

FrustumCullStats SceneFrustumCull::cull(scene::Scene& s, float aspect) {
    FrustumCullStats stats = pending_;
    pending_ = {};
    const double t0 = raster::nowMs();
    const rt::TriangleMeshView mesh{positions_, indices_};
    const std::vector<uint32_t> kept =
        rt::trianglesInFrustum(bvh_->bvh(), mesh, rt::frustumPlanes(s.camera.clipFromWorld(aspect)), &stats.counters);
    // Survivors are in ascending id order, so each mesh's are one run, in their original order.
    size_t k = 0;
    for (size_t m = 0; m < s.meshes.size(); ++m) {
        std::vector<uint32_t>& out = s.meshes[m].indices;
        out.clear();
        for (; k < kept.size() && kept[k] < firstTriangle_[m + 1]; ++k)
            for (int c = 0; c < 3; ++c) out.push_back(indices_[3 * size_t(kept[k]) + c] - firstVertex_[m]);
    }
    stats.trianglesIn = indices_.size() / 3;
    stats.trianglesKept = kept.size();
    stats.cullMs = raster::nowMs() - t0;
    return stats;
}

}  // namespace cuberille::render
