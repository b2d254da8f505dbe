#pragma once
// `cuberille fly`: a flight through a voxel model streamed under a memory budget (render/fly.h)
// along an orbit, a zoom or a keyframe file, with per-frame statistics as CSV and as a plot, and
// frame images on request. A library entry point, so tests and benchmarks run the tool's path.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/fly.h"

namespace CLI {
class App;
}

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

/// Throws scene::InputError for bad options or input (exit code 2). Flies the settings' run of
/// the path (render::FlySettings::firstFrame), writing its frames; final.png only for the run
/// that ends the path.
FlyResult runFly(const FlyOptions& o);
/// Where --save-every writes a frame: OUT_DIR/frame_NNNNN.png.
std::filesystem::path flyFrameFile(const FlyOptions& o, int frame);
/// runFly, then finishFlyCommand.
int runFlyCommand(const FlyOptions& o);
/// What the command writes and prints once the flight is flown: --stats, --plot, the summary.
int finishFlyCommand(const FlyOptions& o, const FlyResult& r);

/// A flight taken apart (python/cuberille/dask): each run's result as JSON (all but the final
/// image, which the last run writes), and the runs joined as one flight reports them.
nlohmann::json flyResultJson(const FlyResult& r);
FlyResult flyResultFromJson(const nlohmann::json& j);
FlyResult joinFlyRuns(std::vector<FlyResult> runs);

/// Adds the `fly` subcommand, whose options fill `o`.
CLI::App* addFlyCommand(CLI::App& app, FlyOptions& o);
/// `fly`'s arguments (the model and options, without "fly") read by the command's own parser;
/// throws scene::InputError with its message.
FlyOptions parseFlyArguments(const std::vector<std::string>& arguments);

/// The CSV's header and one row per frame (for tests and benchmarks).
std::string flyCsv(const FlyResult& r);

}  // namespace cuberille::apps
