#pragma once
// Keeping a hierarchy valid while its mesh deforms (Lauterbach chapter 4).
//
// A refit keeps the tree and recomputes every box bottom-up from the moved triangles: linear
// time, and exact (boxes are min/max). It degrades when triangles that were neighbours drift
// apart, leaving parents large and mostly empty; Lauterbach's criterion (section 4.1.5) measures
// that during the refit itself and says when a rebuild pays.

#include "rt/bvh.h"
#include "rt/bvh_build.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// Refits every box to the mesh's current positions (same indices as at build), in parallel,
/// and returns the degradation: over all inner nodes, the mean of
///     | area(node) / (area(left) + area(right))  -  the same ratio at build time |.
/// 0 for a tree as good as when built (a translated mesh); Lauterbach rebuilds past 0.4.
/// The difference is taken in absolute value: children drifting apart raise a node's ratio, but
/// children swelling over each other (the usual fate of the upper levels of an exploding mesh)
/// lower it toward 1/2, and a signed sum lets the two cancel.
double refitBvh(Bvh& bvh, const TriangleMeshView& mesh);

/// The degradation of the boxes as they stand (no refit), the quantity refitBvh returns.
double bvhDegradation(const Bvh& bvh);

enum class BvhUpdateMethod : uint8_t {
    Refit,    // full bottom-up refit every frame, rebuild past the threshold
    Lazy,     // Larsson's hybrid update (rt/lazy_refit.h), rebuild past the threshold
    Rebuild,  // a new tree every frame
};

/// What one frame's update did and cost.
struct BvhUpdateReport {
    double degradation = 0.0;  // after the refit (before any rebuild it triggered)
    bool measured = false;     // the degradation covers the whole tree (every frame but lazy ones)
    bool rebuilt = false;
    double milliseconds = 0.0;
};

}  // namespace cuberille::rt
