#include "rt/lazy_refit.h"

#include <cmath>

#include "raster/parallel.h"

namespace cuberille::rt {
namespace {

constexpr uint32_t kRefreshing = ~0u;  // a stamp value no frame number takes

}  // namespace

LazyRefit::LazyRefit(Bvh& bvh)
    : bvh_(&bvh), stamp_(new std::atomic<uint32_t>[bvh.nodes.size()]), refreshed_(new std::atomic<uint64_t>(0)) {
    middleDepth_ = bvh.height / 2;
    upperLevels_.resize(size_t(middleDepth_));
    for (uint32_t i = 0; i < bvh.nodes.size(); ++i) {
        stamp_[i].store(0, std::memory_order_relaxed);
        const int depth = bvh.depth[i];
        // The middle level: nodes at depth d, and leaves that end above it.
        if (depth == middleDepth_ || (depth < middleDepth_ && bvh.nodes[i].isLeaf()))
            middleNodes_.push_back(i);
        else if (depth < middleDepth_)
            upperLevels_[size_t(depth)].push_back(i);
    }
}

double LazyRefit::update(const TriangleMeshView& mesh) {
    mesh_ = mesh;
    ++frame_;  // every box below the middle level is stale from here
    if (frame_ == kRefreshing) frame_ = 1;  // wrapped (after 4 billion frames): a stamp of 0 is stale
    refreshed_->store(0, std::memory_order_relaxed);
    if (bvh_->empty()) return 0.0;
    raster::parallelFor(middleNodes_.size(), [&](size_t i) {
        const uint32_t node = middleNodes_[i];
        bvh_->nodes[node].setBox(boxFromTriangles(node));
    });
    double sum = 0.0;
    size_t inner = 0;
    for (size_t level = upperLevels_.size(); level-- > 0;) {
        for (const uint32_t i : upperLevels_[level]) {
            BvhNode& node = bvh_->nodes[i];
            const Aabb l = bvh_->nodes[node.first].box(), r = bvh_->nodes[node.first + 1].box();
            const Aabb box = merged(l, r);
            node.setBox(box);
            sum += std::abs(double(areaRatio(box, l, r)) - double(bvh_->buildAreaRatio[i]));
            ++inner;
        }
    }
    return inner ? sum / double(inner) : 0.0;
}

void LazyRefit::updateAfterFullRefit(const TriangleMeshView& mesh) {
    mesh_ = mesh;
    ++frame_;
    if (frame_ == kRefreshing) frame_ = 1;
    refreshed_->store(0, std::memory_order_relaxed);
    for (size_t i = 0; i < bvh_->nodes.size(); ++i) stamp_[i].store(frame_, std::memory_order_relaxed);
}

Aabb LazyRefit::boxFromTriangles(uint32_t node) const {
    Aabb box;
    const uint32_t first = bvh_->subtreeFirst[node], count = bvh_->subtreeCount[node];
    for (uint32_t i = first; i < first + count; ++i) box.grow(mesh_.triangleBounds(bvh_->primitiveIndices[i]));
    return box;
}

Aabb LazyRefit::currentBox(uint32_t node) const {
    if (bvh_->depth[node] <= middleDepth_) return bvh_->nodes[node].box();
    std::atomic<uint32_t>& stamp = stamp_[node];
    uint32_t seen = stamp.load(std::memory_order_acquire);
    if (seen == frame_) return bvh_->nodes[node].box();
    // Stale. Claim it, refresh it and publish the new stamp (release: the box is written first).
    if (seen != kRefreshing && stamp.compare_exchange_strong(seen, kRefreshing, std::memory_order_acquire)) {
        const Aabb box = boxFromTriangles(node);
        bvh_->nodes[node].setBox(box);
        stamp.store(frame_, std::memory_order_release);
        refreshed_->fetch_add(1, std::memory_order_relaxed);
        return box;
    }
    // Another thread is refreshing it (or just did): the same box, computed here.
    if (seen == frame_) return bvh_->nodes[node].box();
    return boxFromTriangles(node);
}

// Lazy queries read the triangles from the mesh: the tree's leafVertices are as old as its last
// full refit, and refreshing them eagerly would undo the laziness.
RayHit LazyRefit::closestHit(const Ray& ray, const HitFilter* filter) const {
    return detail::traverse<false>(
        *bvh_, ray, [this](uint32_t node) { return currentBox(node); },
        [this](uint32_t slot, int corner) { return mesh_.vertex(bvh_->primitiveIndices[slot], corner); }, nullptr, filter);
}

bool LazyRefit::anyHit(const Ray& ray, const HitFilter* filter) const {
    return detail::traverse<true>(
               *bvh_, ray, [this](uint32_t node) { return currentBox(node); },
               [this](uint32_t slot, int corner) { return mesh_.vertex(bvh_->primitiveIndices[slot], corner); }, nullptr,
               filter)
        .hit();
}

void LazyRefit::refreshAll() const {
    raster::parallelFor(bvh_->nodes.size(), [&](size_t i) { currentBox(uint32_t(i)); });
    gatherLeafVertices(*bvh_, mesh_);
}

size_t LazyRefit::upperNodeCount() const {
    size_t n = middleNodes_.size();
    for (const auto& level : upperLevels_) n += level.size();
    return n;
}

}  // namespace cuberille::rt
