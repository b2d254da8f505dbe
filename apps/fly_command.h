#pragma once
// `cuberille fly`: a flight through a voxel model streamed under a memory budget (render/fly.h)
// along an orbit, a zoom or a keyframe file, with per-frame statistics as CSV and as a plot, and
// frame images on request. A library entry point, so tests and benchmarks run the tool's path.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "render/fly.h"

namespace cuberille::apps {

/// The flight's settings (render/fly.h) and what the tool writes.
struct FlyOptions : render::FlySettings {
    std::filesystem::path outDir;  // images: frame_NNNNN.png every --save-every, and final.png
    int saveEvery = 0;             // 0: only the final image
    std::filesystem::path statsPath, plotPath;
    bool quiet = false;
};

/// The library's result and the process's resident set after each frame (the CSV's last column).
struct FlyResult : render::FlyResult {
    std::vector<uint64_t> residentBytes;
};

/// Throws scene::InputError for bad options or input (exit code 2).
FlyResult runFly(const FlyOptions& o);
int runFlyCommand(const FlyOptions& o);

/// The CSV's header and one row per frame (for tests and benchmarks).
std::string flyCsv(const FlyResult& r);

}  // namespace cuberille::apps
