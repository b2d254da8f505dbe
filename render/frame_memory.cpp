#include "render/frame_memory.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>

#include "raster/framebuffer.h"
#include "scene/input_error.h"

namespace cuberille::render {
namespace {

std::string gib(uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / (1024.0 * 1024.0 * 1024.0));
    return text;
}

uint64_t readNumber(const char* path) {
    std::ifstream in(path);
    std::string word;
    if (!(in >> word) || word == "max") return 0;
    try {
        return std::stoull(word);
    } catch (...) {
        return 0;
    }
}

}  // namespace

FrameMemory frameMemory(const FrameSettings& f) {
    FrameSettings drawn = f;  // a supersampled frame draws N x N times the pixels
    drawn.width *= f.supersample;
    drawn.height *= f.supersample;
    const raster::FramebufferDesc d = framebufferDesc(drawn);
    FrameMemory m;
    m.framebufferBytes = raster::Framebuffer::bytesFor(d);
    const uint64_t resolved = uint64_t(d.widthPixels) * uint64_t(d.heightPixels) * 16;  // float RGBA
    const uint64_t pixels = uint64_t(f.width) * uint64_t(f.height);
    // The resolve's image, the tiles view's second one or the box-filtered one, and the display
    // encoding (at most 8 bytes a pixel: 16-bit RGBA).
    m.imageBytes = resolved + (f.view == View::Tiles || f.supersample > 1 ? pixels * 16 : 0) + pixels * 8;
    if (f.renderer == Renderer::Raytrace)
        m.visibilityBytes = uint64_t(d.widthPixels) * uint64_t(d.heightPixels) * uint64_t(d.samples) * 2 * sizeof(uint32_t);
    return m;
}

uint64_t availableMemoryBytes() {
    uint64_t available = 0;
    std::ifstream meminfo("/proc/meminfo");
    for (std::string key; meminfo >> key;) {
        uint64_t kib = 0;
        meminfo >> kib;
        if (key == "MemAvailable:") {
            available = kib * 1024;
            break;
        }
        meminfo.ignore(256, '\n');
    }
    // A container's limit (cgroup v2) can be far below the machine's memory.
    const uint64_t limit = readNumber("/sys/fs/cgroup/memory.max"), used = readNumber("/sys/fs/cgroup/memory.current");
    if (limit > 0) {
        const uint64_t left = limit > used ? limit - used : 0;
        available = available > 0 ? std::min(available, left) : left;
    }
    return available;
}

void requireFrameMemory(const FrameSettings& f) {
    const FrameMemory need = frameMemory(f);
    const uint64_t available = availableMemoryBytes();
    if (available == 0 || need.totalBytes() <= available) return;
    std::string frame = std::to_string(f.width) + "x" + std::to_string(f.height) + " frame at " + std::to_string(f.msaa) +
                        " sample" + (f.msaa > 1 ? "s" : "");
    if (f.supersample > 1) frame += ", supersampled " + std::to_string(f.supersample) + "x" + std::to_string(f.supersample);
    throw scene::InputError("--width, --height, --msaa" + std::string(f.supersample > 1 ? ", --supersample" : "") + ": a " +
                            frame + " needs about " + gib(need.totalBytes()) + " (a framebuffer of " +
                            gib(need.framebufferBytes) + ": 20 bytes a sample), more than the " + gib(available) +
                            " this machine has available");
}

}  // namespace cuberille::render
