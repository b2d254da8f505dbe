#pragma once
// Larsson and Akenine-Möller's hybrid ("lazy") update of a deforming mesh's hierarchy (2003,
// section 3.2).
//
// A frame's update refits only the upper half of the tree: the boxes at the middle depth
// d = floor(height / 2) straight from the triangles beneath them, and the levels above by merging
// children. The boxes below d are left stale; a ray query refreshes one from its triangles the
// first time it reaches it in the frame. Rays that never go somewhere (occluded or off-screen
// parts of a mesh) never pay for that part's update, and the boxes a query does use are exactly
// the boxes a full refit would give, so every hit is identical to a full refit's.
//
// Queries may run on many threads at once. A stale box is refreshed by whichever thread claims
// it first (a compare-and-swap on the node's frame stamp); a thread that finds it being
// refreshed computes the same box for itself instead of waiting. Boxes are min/max of the same
// triangles whichever thread computes them, so results never depend on scheduling.

#include <atomic>
#include <memory>
#include <vector>

#include "rt/bvh.h"
#include "rt/ray.h"
#include "rt/ray_query.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

class LazyRefit {
public:
    /// Takes over `bvh` for its lifetime; the tree's shape must not change behind its back.
    explicit LazyRefit(Bvh& bvh);

    /// A new frame with the mesh's current positions (same indices as at build): refits the middle
    /// level and above. Returns the degradation measured over the inner nodes above the middle
    /// level (the lower ones are not refitted, so not measured).
    double update(const TriangleMeshView& mesh);

    /// A new frame whose boxes the caller has already refitted in full (refitBvh on the same
    /// tree): every box is current, none is refreshed by queries.
    void updateAfterFullRefit(const TriangleMeshView& mesh);

    RayHit closestHit(const Ray& ray, const HitFilter* filter = nullptr) const;
    bool anyHit(const Ray& ray, const HitFilter* filter = nullptr) const;

    /// Brings every stale box up to date, as a full refit would: for use before anything that
    /// reads the tree's boxes directly.
    void refreshAll() const;

    int middleDepth() const { return middleDepth_; }
    /// Nodes below the middle level whose boxes queries have refreshed this frame.
    uint64_t refreshedThisFrame() const { return refreshed_->load(std::memory_order_relaxed); }
    size_t upperNodeCount() const;

    /// The node's box as of this frame, refreshing it if it is stale (what queries call).
    Aabb currentBox(uint32_t node) const;

private:
    Aabb boxFromTriangles(uint32_t node) const;

    Bvh* bvh_;
    TriangleMeshView mesh_;
    int middleDepth_ = 0;
    uint32_t frame_ = 0;
    std::vector<uint32_t> middleNodes_;              // refitted from triangles each frame
    std::vector<std::vector<uint32_t>> upperLevels_;  // inner nodes above the middle, by depth
    std::unique_ptr<std::atomic<uint32_t>[]> stamp_;  // the frame a lower box was last refreshed
    std::unique_ptr<std::atomic<uint64_t>> refreshed_;
};

}  // namespace cuberille::rt
