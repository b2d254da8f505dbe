#pragma once
// `cuberille accuracy SCENE --out DIR`: what each accuracy knob buys and what it costs, for one
// scene (docs/accuracy.md).
//
// Every setting is a real `cuberille render` command line run as its own process, so a reader can
// rerun any point of the report, and its peak memory is its own. Each knob is swept on its own
// around the balanced preset, and the fast, balanced and exact presets and the tool's defaults are
// run as they are. Each image is compared with the ground truth: the same scene with 256 samples
// per pixel (a 16 x 16 grid, `--supersample 16`), ray-traced shadows, reversed depth, trilinear
// filtering of level-0-dominated textures, and source triangles in place of voxels
// (`--pixel-error 0`).

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/image_error.h"

namespace CLI {
class App;
}

namespace cuberille::apps {

struct AccuracyOptions {
    std::string scene;
    std::filesystem::path outDir;
    int width = 320, height = 180;
    int frames = 3;       // runs per setting; time is their median
    int threads = 0;      // passed to every run (0: all cores)
    float azimuth = 30.0f, elevation = 20.0f;
    int cameraIndex = -1;
    float timeSeconds = 0.0f;
    std::string animation;  // --animation, passed to every render
    bool soft = false;    // soft shadows in every shadowed setting and the truth
    /// --ao N: ambient occlusion in every setting of a 3D scene, N rays a pixel in the balanced
    /// preset, swept as a knob of its own; 0: none.
    int ambientOcclusionRays = 0;
    std::filesystem::path executable;  // the cuberille binary; empty: this process's own
    bool quiet = false;
};

/// One point of the report: a knob at a value, as a render command line.
struct AccuracySetting {
    std::string knob;   // "samples per pixel", "shadow-map size", ..., "preset", "ground truth"
    std::string value;  // as the knob's axis shows it
    double order = 0;   // position along the knob's axis (samples, texels, pixels of error)
    std::vector<std::string> args;  // render options after the scene and the frame options
    bool isDefault = false;         // the tool's defaults (no accuracy option given)
};

struct AccuracyRow {
    AccuracySetting setting;
    std::string id;           // file-name stem of its image and crop
    std::string commandLine;  // the first run's, exactly as run
    std::vector<double> frameMs;  // per run: the frame and its shadow stage, BVH build excluded
    double medianMs = 0, minMs = 0, maxMs = 0;
    double setupMs = 0;       // per run, once per scene: load and the shadow BVH build (median)
    double peakMib = 0;       // the largest resident set of its runs
    bool deterministic = true;  // every run wrote the same image
    ImageError error;
    PixelRect worst;
    bool pareto = false;      // no other row is both as fast and as accurate, and better in one
    bool comparedWithTruth = false;  // error and worst filled in (and its crop written)
};

/// What applies to the scene, found by a small probe render.
struct SceneTraits {
    bool threeD = false, voxel = false, textured = false, shadowed = false;
    std::vector<uint32_t> voxelResolutions;  // voxel models: each level's, finest first
};

struct AccuracyReport {
    AccuracyOptions options;
    SceneTraits traits;
    std::vector<AccuracyRow> rows;       // ground truth last
    std::vector<std::string> notes;      // knobs not swept and why; monotonicity findings
    std::string machine;                 // CPU model and cores
    int threads = 0;
};

/// Runs the sweep and writes report.csv, report.json, index.html, renders/ and crops/ under
/// options.outDir. Throws scene::InputError for bad options or a scene the probe cannot render.
/// It is planAccuracy, runAccuracySetting for each of the plan's runs, and finishAccuracy, the
/// three steps a distributed runner (python/cuberille/dask) takes apart.
AccuracyReport runAccuracy(const AccuracyOptions& options);

/// One setting's renders: `runs` times `cuberille render` (the ground truth at least twice).
struct AccuracyRun {
    AccuracySetting setting;
    std::string id;  // settingId(), or "ground-truth"
    int runs = 1;
    bool groundTruth = false;
};

/// The sweep laid out before any setting renders: the report's options (the executable found),
/// machine, threads and the scene's traits (one probe render), the sweep, and the runs it needs —
/// each distinct command line once, the ground truth last. Creates the output folders.
struct AccuracyPlan {
    AccuracyReport report;  // no rows yet
    std::vector<AccuracySetting> sweep;
    std::vector<AccuracyRun> runs;
};
AccuracyPlan planAccuracy(const AccuracyOptions& options);

/// Renders one run of a plan (`options` as the plan's report holds them) and returns its row:
/// times, memory, determinism and the command line; its first image is left in renders/ID.exr.
/// The ground truth's row is also compared with its own first image (it must be zero).
AccuracyRow runAccuracySetting(const AccuracyOptions& options, const AccuracyRun& run);

/// The report from the rows of the plan's runs, in the plan's order: each setting's image
/// compared with the ground truth's (read back from renders/), the Pareto front, the orders
/// theory predicts, and the report's files written.
AccuracyReport finishAccuracy(AccuracyPlan plan, std::vector<AccuracyRow> rows);

/// Rows and runs as JSON, to carry them between processes (the distributed runner's tasks).
nlohmann::json accuracyRowJson(const AccuracyRow& row);
AccuracyRow accuracyRowFromJson(const nlohmann::json& j);
nlohmann::json accuracyRunJson(const AccuracyRun& run);
AccuracyRun accuracyRunFromJson(const nlohmann::json& j);

/// Adds the `accuracy` subcommand, whose options fill `o`.
CLI::App* addAccuracyCommand(CLI::App& app, AccuracyOptions& o);

/// `accuracy`'s arguments (the scene and options, without "accuracy") read by the command's own
/// parser and checked as the command checks them; throws scene::InputError with its message.
AccuracyOptions parseAccuracyArguments(const std::vector<std::string>& arguments);

/// The sweep for a scene's traits, ground truth last (exposed for tests).
std::vector<AccuracySetting> accuracySweep(const SceneTraits& traits, bool soft, int ambientOcclusionRays = 0);

/// The ground truth's ambient occlusion rays a pixel (with --ao): each of its 256 samples a pixel
/// traces them, so a final pixel averages 16,384 rays, whose noise (below 1/16,384 for the
/// stratified set, turned differently at each sample) is far under one 8-bit level.
inline constexpr int kTruthOcclusionRays = 64;
/// The values the "ambient occlusion rays" knob takes.
inline constexpr int kOcclusionRaysSwept[] = {1, 4, 16, 64};

/// What applies to the scene, from a 64 x 36 render with ray-traced shadows (3D scenes):
/// textures sampled, a light that casts shadows. `options.executable` must be set.
SceneTraits probeScene(const AccuracyOptions& options);

/// The file-name stem of a setting's image and crop ("samples-per-pixel-4").
std::string settingId(const AccuracySetting& setting);

/// The whole subcommand; returns the exit code.
int runAccuracyCommand(const AccuracyOptions& options);

}  // namespace cuberille::apps
