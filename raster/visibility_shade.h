#pragma once
// Deferred shade: the shade stage run over a visibility buffer that something other than the
// frame's own depth test filled — the camera rays of the ray-tracing renderer, or the shadow
// stage's visibility buffer, which a shadowed raster frame of one sample shades instead of drawing
// the scene again (render/renderer.cpp).
//
// Each sample names the triangle of a recorded draw it sees (Burns and Hunt's visibility buffer,
// 2013, per sample). For every pixel, each distinct triangle among its samples is shaded once, at
// the pixel centre, with the samples that see it as its pass mask: the multisample semantics of
// the forward path (raster/shade.h), through the same shading models. The triangle's set-up is
// the front end's own — snapped to 1/256 pixel, clipped where it crosses a clip plane — so its
// barycentrics, texture derivatives and facing are those the rasterizer shades with: where the
// buffer names the triangle the depth test would have kept, the sample's colour and depth are the
// forward path's bit for bit (VisibilityShade.GivesTheForwardFramesBitsWhereItSeesWhatTheDepthTestKept).
//
// Every draw is merged as opaque: what the buffer names is what the sample shows, so a masked or
// blended draw's alpha is not applied here (its caller decides what such draws mean).
//
// A sample can name a triangle the front end cannot set up: one whose snapped vertices have zero
// area (a sliver narrower than 1/256 pixel that an exact ray still meets). It has no barycentrics
// to shade with; the sample keeps the clear colour and is counted (samplesWithoutSetUp).

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "raster/draw.h"
#include "raster/framebuffer.h"
#include "raster/stats.h"

namespace cuberille::raster {

struct VisibilityBuffer {
    static constexpr uint32_t kNone = ~0u;
    int width = 0, height = 0, samples = 1;
    /// Per sample at (y x width + x) x samples + s (the standard pattern's order): the index of
    /// the draw among the frame's recorded draws, and of the triangle within the draw; kNone
    /// draw: the sample sees nothing.
    std::vector<uint32_t> draw, triangle;

    void reset(int widthPixels, int heightPixels, int sampleCount) {
        width = widthPixels, height = heightPixels, samples = sampleCount;
        const size_t n = size_t(widthPixels) * size_t(heightPixels) * size_t(sampleCount);
        draw.assign(n, kNone);
        triangle.assign(n, kNone);
    }
};

struct VisibilityShadeStats {
    uint64_t trianglesSeen = 0;         // distinct triangles the buffer names
    uint64_t samplesWithoutSetUp = 0;   // samples whose triangle has zero area once snapped
    double vertexMs = 0, setupMs = 0, shadeMs = 0;
};

/// What the stage keeps from frame to frame: per draw, which triangles were seen, their set-ups
/// and the vertex stage's outputs. Kept by the Pipeline, so a sequence of frames reuses that memory
/// instead of taking fresh pages every frame (the dragon at 1280x720, one sample: 871k triangles'
/// tables and 437k vertices' outputs; faulting them in took 13 ms of a 40 ms frame).
struct VisibilityShadeStorage;
std::unique_ptr<VisibilityShadeStorage, void (*)(VisibilityShadeStorage*)> makeVisibilityShadeStorage();

/// Shades `seen` into fb (begun, with colour; its size and sample count) from the frame's draws,
/// which must be in clip space (PositionSpace::Clip). Adds the stages' work to `counters`.
/// Deterministic: the same bits for every thread count.
VisibilityShadeStats shadeVisibility(std::span<const DrawCall> draws, const VisibilityBuffer& seen, Framebuffer& fb,
                                     StageCounters& counters, VisibilityShadeStorage& storage);

}  // namespace cuberille::raster
