#include "rt/deforming_bvh.h"

#include "raster/clock.h"

namespace cuberille::rt {

DeformingBvh::DeformingBvh(const TriangleMeshView& mesh, BvhUpdateMethod method, const BvhBuildOptions& build,
                           double rebuildThreshold, RayQueryTree queries)
    : method_(method),
      build_(build),
      threshold_(rebuildThreshold),
      mesh_(mesh),
      queries_(queries) {
    bvh_ = std::make_unique<Bvh>(buildBvh(mesh, build_));
    startLazy();
    if (usesWide()) wide_ = collapseToWideBvh(*bvh_);
}

// Every box of a new tree is current, so the lazy updater starts with none stale: the pose is
// answered before any update, and no query refreshes what the build just computed.
void DeformingBvh::startLazy() {
    if (method_ != BvhUpdateMethod::Lazy) return;
    lazy_.emplace(*bvh_);
    lazy_->updateAfterFullRefit(mesh_);
}

void DeformingBvh::rebuild() {
    lazy_.reset();
    *bvh_ = buildBvh(mesh_, build_);
    startLazy();
    if (usesWide()) wide_ = collapseToWideBvh(*bvh_);
    ++rebuilds_;
}

BvhUpdateReport DeformingBvh::update(const TriangleMeshView& mesh) {
    const double t0 = raster::nowMs();
    mesh_ = mesh;
    BvhUpdateReport report;
    switch (method_) {
        case BvhUpdateMethod::Rebuild:
            rebuild();
            report.rebuilt = true;
            break;
        case BvhUpdateMethod::Refit:
            report.degradation = refitBvh(*bvh_, mesh);
            report.measured = true;
            break;
        case BvhUpdateMethod::Lazy:
            if (++frame_ % kLazyCriterionInterval == 0) {
                report.degradation = refitBvh(*bvh_, mesh);
                report.measured = true;
                lazy_->updateAfterFullRefit(mesh);
            } else {
                report.degradation = lazy_->update(mesh);
            }
            break;
    }
    // Lauterbach 4.1.5: past the threshold the refitted tree costs more to trace than a rebuild.
    if (report.measured && report.degradation > threshold_) {
        rebuild();
        report.rebuilt = true;
    } else if (method_ == BvhUpdateMethod::Refit && usesWide()) {
        refreshWideBvh(wide_, *bvh_);  // a rebuild collapses the new tree instead
    }
    report.milliseconds = raster::nowMs() - t0;
    return report;
}

RayHit DeformingBvh::closestHit(const Ray& ray) const {
    if (lazy_) return lazy_->closestHit(ray);
    return usesWide() ? rt::closestHit(wide_, ray) : rt::closestHit(*bvh_, mesh_, ray);
}

RayHit DeformingBvh::closestHit(const Ray& ray, const HitFilter& filter) const {
    if (lazy_) return lazy_->closestHit(ray, &filter);
    return usesWide() ? rt::closestHit(wide_, ray, filter) : rt::closestHit(*bvh_, mesh_, ray, filter);
}

void DeformingBvh::closestHits(std::span<const Ray> rays, std::span<RayHit> hits, const HitFilter& filter) const {
    if (usesWide() && !lazy_) return rt::closestHits(wide_, rays, hits, &filter);
    for (size_t i = 0; i < rays.size(); ++i) hits[i] = closestHit(rays[i], filter);
}

bool DeformingBvh::anyHit(const Ray& ray, const HitFilter* filter) const {
    if (lazy_) return lazy_->anyHit(ray, filter);
    return usesWide() ? rt::anyHit(wide_, ray, filter) : rt::anyHit(*bvh_, mesh_, ray, filter);
}

void DeformingBvh::anyHits(std::span<const Ray> rays, std::span<uint8_t> occluded, const HitFilter* filter) const {
    if (usesWide() && !lazy_) return rt::anyHits(wide_, rays, occluded, filter);
    for (size_t i = 0; i < rays.size(); ++i) occluded[i] = anyHit(rays[i], filter);
}

const Bvh& DeformingBvh::bvh() const {
    if (lazy_) lazy_->refreshAll();
    return *bvh_;
}

}  // namespace cuberille::rt
