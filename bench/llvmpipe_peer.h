#pragma once
// Mesa's llvmpipe through OSMesa, drawing the same triangles with the same per-pixel shading as
// Cuberille (raster/shade.h in GLSL: Lambert or the metallic-roughness BRDF over the scene's
// lights, the same textures), for side-by-side timing. Thread count: LP_NUM_THREADS, read once
// per process.

#include <memory>
#include <vector>

#include "scene/procedural.h"

namespace cuberille::bench {

class LlvmpipePeer {
public:
    /// Creates the context; msaa 1 draws to the OSMesa buffer, more to a multisampled FBO that
    /// is resolved with glBlitFramebuffer each frame.
    LlvmpipePeer(int width, int height, int msaa);
    ~LlvmpipePeer();

    /// Uploads the scene's meshes into buffer objects (not timed).
    void upload(const scene::Scene& scene);
    /// Renders one frame and waits for it (glFinish); returns milliseconds.
    double renderFrame(const scene::Scene& scene);
    /// A depth-only pass of the same view, as a shadow map or a visibility buffer's depth is
    /// drawn: colour writes off, a position-only program with an empty fragment stage, every mesh
    /// an opaque caster with the scene's culling; no resolve. Returns milliseconds; the frame's
    /// covered pixels (depth below the far plane, at 1 sample) are depthCoverage().
    double renderDepthFrame(const scene::Scene& scene);
    /// At 1 sample, after renderDepthFrame: per pixel, bottom row first, whether depth was written.
    std::vector<bool> depthCoverage() const;
    static bool available();
    /// The last frame's resolved pixels: RGBA 8-bit, bottom row first (OpenGL's order).
    const std::vector<unsigned char>& pixels() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cuberille::bench
