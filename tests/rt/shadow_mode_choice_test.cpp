// --shadows auto's cost model (rt/shadow_mode_choice.h) on the workloads its constants were
// measured on: the choices the measurements made (docs/ray_tracing.md) come out of it, and the
// predictions move the way the work does.

#include <gtest/gtest.h>

#include "rt/shadow_mode_choice.h"

namespace cuberille::rt {
namespace {

/// The dragon on its floor at 1280x720: 871k caster triangles, about 450k receivers, one 2048-texel map.
ShadowWorkload dragonFrame() {
    ShadowWorkload w;
    w.receivers = 450'000;
    w.casterTriangles = 871'416;
    w.mapTexels = 2048ull * 2048ull;
    return w;
}

TEST(ShadowModeChoice, OneHardFrameIsRayTracedAndATurntableThatSharesTheMapIsHybrid) {
    ShadowWorkload w = dragonFrame();
    const ShadowModeChoice single = chooseShadowMode(w);
    EXPECT_EQ(single.mode, ShadowMode::RayTraced) << "measured: 46 ms of rays against 42 ms of map, 18 of mask, 116 of adjacency";
    double previous = single.predictedHybridMs;
    for (const int frames : {2, 8, 36, 360}) {
        w.framesSharingMap = frames;
        const ShadowModeChoice shared = chooseShadowMode(w);
        EXPECT_LT(shared.predictedHybridMs, previous) << frames << " frames share the map and the adjacency";
        EXPECT_EQ(shared.predictedRayTracedMs, single.predictedRayTracedMs) << "rays are paid every frame";
        previous = shared.predictedHybridMs;
    }
    w.framesSharingMap = 36;
    EXPECT_EQ(chooseShadowMode(w).mode, ShadowMode::Hybrid) << "measured: 26 ms a frame against 48";
}

TEST(ShadowModeChoice, SoftShadowsAreHybridEvenForOneFrame) {
    ShadowWorkload w = dragonFrame();
    w.soft = true;
    w.raysPerReceiver = 16;
    const ShadowModeChoice c = chooseShadowMode(w);
    EXPECT_EQ(c.mode, ShadowMode::Hybrid) << "measured: 338 ms against 476";
    EXPECT_GT(c.predictedRayTracedMs, 16.0 * chooseShadowMode(dragonFrame()).predictedRayTracedMs - 1e-9);
}

TEST(ShadowModeChoice, AMapLargerThanTheRaysItSavesIsNotDrawn) {
    ShadowWorkload w = dragonFrame();
    w.soft = true;
    w.raysPerReceiver = 16;
    w.receivers = 2'000;  // a thumbnail's worth of receivers
    w.mapTexels = 6ull * 4096ull * 4096ull;  // a point light's cube of 4096-texel faces
    EXPECT_EQ(chooseShadowMode(w).mode, ShadowMode::RayTraced);
    w.receivers = 0;
    EXPECT_EQ(chooseShadowMode(w).mode, ShadowMode::RayTraced) << "nothing to shade: the reference, at no cost";
}

}  // namespace
}  // namespace cuberille::rt
