#pragma once
// The memory a frame needs, predicted before anything is allocated, and checked against what the
// machine has: a 16384² frame at 16 samples needs 80 GiB of framebuffer and is refused with that
// figure, not ended by std::bad_alloc halfway (docs/cli.md, "Memory").

#include <cstdint>
#include <string>

#include "render/frame_settings.h"

namespace cuberille::render {

struct FrameMemory {
    uint64_t framebufferBytes = 0;  // raster::Framebuffer::bytesFor the frame (N² times the pixels when supersampling)
    uint64_t imageBytes = 0;        // the resolved float RGBA image(s) and the display encoding
    /// --renderer raytrace: the visibility buffer the camera rays fill (8 bytes a sample: draw and
    /// triangle, raster/visibility_shade.h).
    uint64_t visibilityBytes = 0;
    uint64_t totalBytes() const { return framebufferBytes + imageBytes + visibilityBytes; }
};

/// What render() will allocate for the frame itself, beside the scene (which is already loaded).
FrameMemory frameMemory(const FrameSettings& settings);

/// Memory this process can still take: the smaller of Linux's MemAvailable and what the cgroup's
/// memory.max leaves; 0 when neither can be read (then nothing is refused).
uint64_t availableMemoryBytes();

/// Throws scene::InputError naming --width, --height, --msaa (and --supersample) when the frame
/// needs more than is available.
void requireFrameMemory(const FrameSettings& settings);

}  // namespace cuberille::render
