#pragma once
// Small helpers shared by the raster tests: render a scene through the real pipeline and read
// individual samples back.

#include <glm/glm.hpp>

#include "raster/framebuffer.h"
#include "raster/limits.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/tri_scene.h"

namespace cuberille::testing {

inline glm::vec4 sampleColor(const raster::Framebuffer& fb, int x, int y, int s) {
    const int tile = (y / raster::kTileSizePixels) * fb.tilesX() + x / raster::kTileSizePixels;
    if (!fb.tileTouched(tile)) return fb.desc().clearColor;
    const size_t i = (size_t(y % raster::kTileSizePixels) * raster::kTileSizePixels +
                      size_t(x % raster::kTileSizePixels)) * fb.samples() + s;
    return fb.tileColor(tile)[i];
}

inline raster::FramebufferDesc frame(int width, int height, int samples) {
    raster::FramebufferDesc d;
    d.widthPixels = width;
    d.heightPixels = height;
    d.samples = samples;
    return d;
}

/// One frame of one draw: begin, draw, end.
inline void drawFrame(raster::Pipeline& p, const raster::FramebufferDesc& desc, const raster::DrawCall& draw) {
    p.beginFrame(desc);
    p.draw(draw);
    p.endFrame();
}

/// One draw into a fresh 1-sample frame, resolved: the image and the stage counters.
struct ResolvedDraw {
    raster::Image image;
    raster::StageCounters counters;
};
inline ResolvedDraw renderResolved(const raster::DrawCall& draw, int width, int height) {
    raster::Pipeline p;
    drawFrame(p, frame(width, height, 1), draw);
    ResolvedDraw r;
    raster::resolveColor(p.framebuffer(), r.image);
    r.counters = p.stats().counters;
    return r;
}

inline void renderTri(raster::Pipeline& p, const scene::TriScene& s, int width, int height,
                      int samples, bool recordOverdraw = false) {
    raster::FramebufferDesc d = frame(width, height, samples);
    d.recordOverdraw = recordOverdraw;
    drawFrame(p, d, s.drawCall());
}

}  // namespace cuberille::testing
