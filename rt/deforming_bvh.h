#pragma once
// A hierarchy that follows a deforming mesh from frame to frame: refitted (fully, or lazily after
// Larsson) while Lauterbach's degradation stays under the threshold, rebuilt when it passes it,
// or rebuilt every frame. Each update reports what it did and what it cost.
//
// Ray queries go through the eight-wide tree collapsed from the binary one (rt/wide_bvh.h), kept
// current after each refit or rebuild, except under the lazy method, whose point is to refresh
// only the boxes rays reach: that walks the binary tree. Users that only walk the binary tree (the
// frustum cull) ask for no wide tree and pay nothing for it.

#include <memory>
#include <optional>

#include "rt/bvh.h"
#include "rt/bvh_build.h"
#include "rt/bvh_refit.h"
#include "rt/lazy_refit.h"
#include "rt/ray_query.h"
#include "rt/wide_bvh.h"

namespace cuberille::rt {

/// Lazy updates refit only the upper half of the tree, and the upper levels alone cannot tell
/// rigid motion from an explosion (a turning mesh changes their ratios by up to 0.19, an exploding
/// one levels off near 0.39: tests/rt/bvh_refit_test.cpp). So every this many frames the lazy
/// method refits the whole tree instead, and Lauterbach's criterion is decided on that.
constexpr int kLazyCriterionInterval = 8;

/// Which tree answers a DeformingBvh's ray queries (the lazy method always uses the binary one).
enum class RayQueryTree : uint8_t {
    Wide,    // collapsed from the binary tree: vector tests of eight boxes and four triangles
    Binary,  // the binary tree itself: no copy, for users that never trace rays
};

class DeformingBvh {
public:
    /// Builds over the first pose. `rebuildThreshold` is Lauterbach's 0.4 by default.
    DeformingBvh(const TriangleMeshView& mesh, BvhUpdateMethod method, const BvhBuildOptions& build = {},
                 double rebuildThreshold = 0.4, RayQueryTree queries = RayQueryTree::Wide);

    /// The next pose: same indices, moved positions (which must stay alive until the next update).
    BvhUpdateReport update(const TriangleMeshView& mesh);

    RayHit closestHit(const Ray& ray) const;
    /// The closest hit among the triangles not skipped (HitFilter, by the mesh's ids).
    RayHit closestHit(const Ray& ray, const HitFilter& filter) const;
    bool anyHit(const Ray& ray, const HitFilter* filter = nullptr) const;
    /// anyHit for each of `rays`: through the wide tree as packets (rt/wide_bvh.h, anyHits), else
    /// one at a time. The same answers either way.
    void anyHits(std::span<const Ray> rays, std::span<uint8_t> occluded, const HitFilter* filter = nullptr) const;
    /// closestHit(ray, filter) for each of `rays`: through the wide tree as packets
    /// (rt/wide_bvh.h, closestHits), else one at a time. The same hits either way.
    void closestHits(std::span<const Ray> rays, std::span<RayHit> hits, const HitFilter& filter) const;

    /// The tree with every box current (a lazy tree is brought up to date first).
    const Bvh& bvh() const;
    int rebuilds() const { return rebuilds_; }

private:
    void rebuild();
    void startLazy();
    bool usesWide() const { return queries_ == RayQueryTree::Wide && method_ != BvhUpdateMethod::Lazy; }

    BvhUpdateMethod method_;
    BvhBuildOptions build_;
    double threshold_;
    TriangleMeshView mesh_;
    std::unique_ptr<Bvh> bvh_;  // stable address: the lazy updater holds it
    std::optional<LazyRefit> lazy_;
    RayQueryTree queries_;
    WideBvh wide_;  // when usesWide()
    int rebuilds_ = 0;
    int frame_ = 0;
};

}  // namespace cuberille::rt
