#pragma once
// --shadows auto: which exact mode a light's shadows cost least in, hybrid or ray-traced (map
// mode is never chosen: it is not the reference's image). Issue 27; docs/ray_tracing.md.
//
// Ray tracing pays a ray (N x N soft) for every receiver. Hybrid pays for its map — nothing when
// the map held is kept, a share when a sequence will keep the one drawn now — its edge adjacency
// once per pose, a map lookup for every receiver, and rays for the share of receivers it marks,
// which are the expensive ones (they pass by silhouettes). The prediction is a cost model over
// counts the frame knows before either mode runs, with per-unit costs measured once by
// `shadow_bench` on the CI machine kind, not timings of this run: a choice from this run's
// clocks would let the image depend on timing (hybrid differs from the reference on a few
// sub-texel pixels), breaking the promise that a frame's bits depend on its input alone. For
// the same reason the model reads nothing an earlier frame left — not the map held, not the
// adjacency built, not the share of pixels marked last time: a frame rendered alone, twice, or
// from the middle of a sequence (the distributed runner's runs) chooses as it does in the
// sequence. A map a sequence keeps is charged to each of its frames in equal shares instead.

#include <cstdint>

#include "rt/shadows.h"

namespace cuberille::rt {

/// What one light's shadows will ask of a frame, known before either mode runs.
struct ShadowWorkload {
    uint64_t receivers = 0;        // pixels with a surface seen (every one may face the light)
    int raysPerReceiver = 1;       // N x N for soft shadows
    bool soft = false;
    uint64_t casterTriangles = 0;
    uint64_t mapTexels = 0;        // size x size x faces
    /// Frames of the command that one drawing of the map serves (and one edge adjacency: the
    /// casters stay still through them); 1 for a single frame or an animation's pose.
    int framesSharingMap = 1;
};

struct ShadowModeChoice {
    ShadowMode mode = ShadowMode::RayTraced;
    double predictedHybridMs = 0.0, predictedRayTracedMs = 0.0;
};

/// Hybrid when its predicted cost is below ray tracing's; ray-traced otherwise (ties too: the
/// reference itself).
ShadowModeChoice chooseShadowMode(const ShadowWorkload& work);

}  // namespace cuberille::rt
