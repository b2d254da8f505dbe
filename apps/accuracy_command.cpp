#include "apps/accuracy_command.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <fcntl.h>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>

#include "apps/accuracy_report.h"
#include "apps/image_io.h"
#include "apps/render_options_cli.h"
#include "raster/limits.h"
#include "raster/parallel.h"
#include "scene/input_error.h"
#include "scene/file_names.h"

extern char** environ;

namespace cuberille::apps {
namespace {

namespace fs = std::filesystem;

struct RunOutcome {
    double frameMs = 0, setupMs = 0, peakMib = 0;
    raster::Image image;
    std::string commandLine;
    nlohmann::json stats;  // the run's --stats
};

void validate(const AccuracyOptions& o);
AccuracyRow runSetting(const AccuracyOptions& o, const AccuracySetting& s, const std::string& id, int runs,
                       raster::Image& firstImage, raster::Image& lastImage);
void compareWithTruth(AccuracyRow& row, const raster::Image& image, const raster::Image& truth, const fs::path& outDir);
void markParetoFront(std::vector<AccuracyRow>& rows);
void checkMonotone(const std::vector<AccuracyRow>& rows, std::vector<std::string>& notes);
void noteKnobsNotSwept(const SceneTraits& traits, std::vector<std::string>& notes);
std::string machineDescription();

}  // namespace

// The report in four steps: find what applies to the scene, render the ground truth, render every
// setting and compare it with the truth, then mark the Pareto front and check the orders theory
// predicts. The truth renders first, so each setting is compared with it as it finishes.
AccuracyReport runAccuracy(const AccuracyOptions& options) {
    AccuracyPlan plan = planAccuracy(options);
    const AccuracyOptions& o = plan.report.options;
    const AccuracyRun& truthRun = plan.runs.back();
    raster::Image truth, truthAgain;
    AccuracyRow truthRow = runSetting(o, truthRun.setting, truthRun.id, truthRun.runs, truth, truthAgain);
    compareWithTruth(truthRow, truthAgain, truth, o.outDir);
    std::vector<AccuracyRow> rows;
    for (size_t i = 0; i + 1 < plan.runs.size(); ++i) {
        const AccuracyRun& run = plan.runs[i];
        raster::Image first, last;
        AccuracyRow row = runSetting(o, run.setting, run.id, run.runs, first, last);
        compareWithTruth(row, first, truth, o.outDir);
        if (!o.quiet) {
            std::printf("  %-24s %-10s %9.2f ms  RMSE %.5f\n", run.setting.knob.c_str(), run.setting.value.c_str(),
                        row.medianMs, row.error.rmse);
            std::fflush(stdout);  // progress, also when stdout is a file
        }
        rows.push_back(std::move(row));
    }
    rows.push_back(std::move(truthRow));
    return finishAccuracy(std::move(plan), std::move(rows));
}

AccuracyPlan planAccuracy(const AccuracyOptions& options) {
    validate(options);
    AccuracyPlan plan;
    AccuracyReport& report = plan.report;
    report.options = options;
    if (report.options.executable.empty()) report.options.executable = fs::read_symlink("/proc/self/exe");
    const AccuracyOptions& o = report.options;
    fs::create_directories(o.outDir / "renders");
    fs::create_directories(o.outDir / "crops");
    fs::create_directories(o.outDir / "logs");
    report.machine = machineDescription();
    report.threads = o.threads > 0 ? o.threads : raster::hardwareThreads();
    report.traits = probeScene(o);
    if (o.ambientOcclusionRays > 0 && !report.traits.threeD)
        throw scene::InputError("--ao: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + o.scene);
    plan.sweep = accuracySweep(report.traits, o.soft, o.ambientOcclusionRays);
    std::set<std::vector<std::string>> planned;  // identical command lines run once
    for (size_t i = 0; i + 1 < plan.sweep.size(); ++i) {
        const AccuracySetting& s = plan.sweep[i];
        if (planned.insert(s.args).second) plan.runs.push_back({s, settingId(s), o.frames, false});
    }
    // The truth runs at least twice: its row compares the last run with the first, so a report
    // whose ground truth is not zero against itself shows it.
    plan.runs.push_back({plan.sweep.back(), "ground-truth", std::max(2, o.frames), true});
    return plan;
}

AccuracyRow runAccuracySetting(const AccuracyOptions& options, const AccuracyRun& run) {
    raster::Image first, last;
    AccuracyRow row = runSetting(options, run.setting, run.id, run.runs, first, last);
    if (run.groundTruth) compareWithTruth(row, last, first, options.outDir);
    return row;
}

AccuracyReport finishAccuracy(AccuracyPlan plan, std::vector<AccuracyRow> rows) {
    if (rows.size() != plan.runs.size() || rows.empty())
        throw std::invalid_argument("finishAccuracy: one row per run of the plan");
    AccuracyReport& report = plan.report;
    const AccuracyOptions& o = report.options;
    const fs::path renders = o.outDir / "renders";
    std::optional<raster::Image> truth;  // read back only for rows rendered elsewhere
    std::map<std::vector<std::string>, AccuracyRow> byCommand;
    for (size_t i = 0; i + 1 < rows.size(); ++i) {
        AccuracyRow& row = rows[i];
        if (!row.comparedWithTruth) {
            if (!truth) truth = readImage(renders / (rows.back().id + ".exr"));
            compareWithTruth(row, readImage(renders / (row.id + ".exr")), *truth, o.outDir);
        }
        byCommand.emplace(plan.runs[i].setting.args, row);
    }
    for (size_t i = 0; i + 1 < plan.sweep.size(); ++i) {
        AccuracyRow row = byCommand.at(plan.sweep[i].args);
        row.setting = plan.sweep[i];  // the same run, listed under each knob whose command line it is
        report.rows.push_back(std::move(row));
    }
    report.rows.push_back(std::move(rows.back()));
    markParetoFront(report.rows);
    noteKnobsNotSwept(report.traits, report.notes);
    checkMonotone(report.rows, report.notes);
    writeAccuracyReport(report);
    return std::move(report);
}

nlohmann::json accuracyRunJson(const AccuracyRun& run) {
    const AccuracySetting& s = run.setting;
    return {{"knob", s.knob}, {"value", s.value}, {"order", s.order}, {"args", s.args}, {"isDefault", s.isDefault},
            {"id", run.id},   {"runs", run.runs}, {"groundTruth", run.groundTruth}};
}

AccuracyRun accuracyRunFromJson(const nlohmann::json& j) {
    AccuracyRun run;
    AccuracySetting& s = run.setting;
    j.at("knob").get_to(s.knob), j.at("value").get_to(s.value), j.at("order").get_to(s.order);
    j.at("args").get_to(s.args), j.at("isDefault").get_to(s.isDefault);
    j.at("id").get_to(run.id), j.at("runs").get_to(run.runs), j.at("groundTruth").get_to(run.groundTruth);
    return run;
}

// Every field, so a row rebuilt from its JSON is the row (the error's infinite PSNR as null).
nlohmann::json accuracyRowJson(const AccuracyRow& r) {
    const ImageError& e = r.error;
    nlohmann::json setting = accuracyRunJson({r.setting, r.id, 0, false});
    return {{"setting", setting},
            {"commandLine", r.commandLine},
            {"frameMs", r.frameMs},
            {"medianMs", r.medianMs},
            {"minMs", r.minMs},
            {"maxMs", r.maxMs},
            {"setupMs", r.setupMs},
            {"peakMib", r.peakMib},
            {"deterministic", r.deterministic},
            {"error", {e.rmse, std::isfinite(e.psnrDb) ? nlohmann::json(e.psnrDb) : nlohmann::json(nullptr), e.maxError,
                       e.shareOver1, e.shareOver8}},
            {"worst", {r.worst.x, r.worst.y, r.worst.width, r.worst.height}},
            {"pareto", r.pareto},
            {"comparedWithTruth", r.comparedWithTruth}};
}

AccuracyRow accuracyRowFromJson(const nlohmann::json& j) {
    AccuracyRow r;
    const AccuracyRun run = accuracyRunFromJson(j.at("setting"));
    r.setting = run.setting, r.id = run.id;
    j.at("commandLine").get_to(r.commandLine), j.at("frameMs").get_to(r.frameMs);
    j.at("medianMs").get_to(r.medianMs), j.at("minMs").get_to(r.minMs), j.at("maxMs").get_to(r.maxMs);
    j.at("setupMs").get_to(r.setupMs), j.at("peakMib").get_to(r.peakMib), j.at("deterministic").get_to(r.deterministic);
    const nlohmann::json& e = j.at("error");
    r.error = {e.at(0).get<double>(), e.at(1).is_null() ? std::numeric_limits<double>::infinity() : e.at(1).get<double>(),
               e.at(2).get<double>(), e.at(3).get<double>(), e.at(4).get<double>()};
    const nlohmann::json& w = j.at("worst");
    r.worst = {w.at(0).get<int>(), w.at(1).get<int>(), w.at(2).get<int>(), w.at(3).get<int>()};
    j.at("pareto").get_to(r.pareto), j.at("comparedWithTruth").get_to(r.comparedWithTruth);
    return r;
}

CLI::App* addAccuracyCommand(CLI::App& app, AccuracyOptions& o) {
    CLI::App* a = app.add_subcommand(
        "accuracy", "Sweep every accuracy knob that applies to a scene against a 256-sample ground truth: time, "
                    "memory and error per setting, as report.csv, report.json and index.html with plots");
    a->add_option("scene", o.scene, "A scene as `render` takes it")->required();
    a->add_option("--out", o.outDir, "Directory for the report, its renders and crops")->required();
    a->add_option("--width", o.width, "Image width in pixels (the truth renders 16 times as wide)")->capture_default_str();
    a->add_option("--height", o.height, "Image height in pixels")->capture_default_str();
    a->add_option("--frames", o.frames, "Runs per setting; time is their median")->capture_default_str();
    a->add_option("--threads", o.threads, "Worker threads of every run (0 = all cores)")->capture_default_str();
    a->add_option("--azimuth", o.azimuth, "Camera azimuth for mesh files and voxel models, degrees")->capture_default_str();
    a->add_option("--elevation", o.elevation, "Camera elevation, degrees")->capture_default_str();
    a->add_option("--camera-index", o.cameraIndex, "Use the file's N-th camera (glTF)");
    a->add_option("--time", o.timeSeconds, "glTF: the animation's pose at this time, in seconds")->capture_default_str();
    a->add_option("--animation", o.animation, "glTF: the animation posed, by name or index (default: the first)");
    a->add_flag("--soft", o.soft, "Soft shadows in every shadowed setting and the truth");
    a->add_option("--ao", o.ambientOcclusionRays,
                  "3D scenes: ambient occlusion in every setting, N rays a pixel in the balanced preset, and its "
                  "rays a pixel swept as a knob (the truth traces " + std::to_string(kTruthOcclusionRays) +
                  " at each of its samples)");
    a->add_flag("--quiet", o.quiet, "Print nothing on success");
    return a;
}

AccuracyOptions parseAccuracyArguments(const std::vector<std::string>& arguments) {
    AccuracyOptions o;
    parseSubcommandArguments("accuracy", arguments, [&](CLI::App& app) { addAccuracyCommand(app, o); });
    validate(o);
    return o;
}

int runAccuracyCommand(const AccuracyOptions& o) {
    const AccuracyReport report = runAccuracy(o);
    if (!o.quiet)
        std::printf("wrote %zu settings to %s (index.html, report.csv, report.json)\n", report.rows.size(),
                    o.outDir.c_str());
    return 0;
}

// ---------------------------------------------------------------------------------------------
// The sweep

namespace {

// The accuracy knobs a render command line sets; only those that apply to the scene are written.
struct Knobs {
    int msaa = 4;
    std::string textureFilter = "trilinear";
    std::string shadows = "hybrid";
    int mapSizeTexels = 1024;
    float pixelError = 1.0f;
    bool reversedDepth = false;
    uint32_t voxelResolution = 0;  // 0: the model's finest
    int supersample = 1;
    int occlusionRays = 0;  // --ao, for 3D scenes; 0: none
    std::string renderer = "raster";  // 3D scenes and voxel models: --renderer
    std::string accel = "bvh";        // with --renderer raytrace: --accel
};

std::string formatNumber(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

std::vector<std::string> knobArgs(const Knobs& k, const SceneTraits& t, bool soft) {
    std::vector<std::string> a;
    if (k.supersample > 1) a.insert(a.end(), {"--supersample", std::to_string(k.supersample)});
    a.insert(a.end(), {"--msaa", std::to_string(k.msaa)});
    if (t.textured) a.insert(a.end(), {"--texture-filter", k.textureFilter});
    if (t.shadowed) {
        a.insert(a.end(), {"--shadows", k.shadows});
        if (k.shadows == "map" || k.shadows == "hybrid" || k.shadows == "auto")
            a.insert(a.end(), {"--shadow-map-size", std::to_string(k.mapSizeTexels)});
        if (soft && k.shadows != "none") a.push_back("--soft");
    }
    if (t.threeD && k.occlusionRays > 0) a.insert(a.end(), {"--ao", std::to_string(k.occlusionRays)});
    if ((t.threeD || t.voxel) && k.renderer != "raster") a.insert(a.end(), {"--renderer", k.renderer, "--accel", k.accel});
    if (t.voxel) a.insert(a.end(), {"--pixel-error", formatNumber(k.pixelError)});
    if ((t.threeD || t.voxel) && k.reversedDepth) a.insert(a.end(), {"--depth", "reversed"});
    if (t.voxel && k.voxelResolution) a.insert(a.end(), {"--voxel-resolution", std::to_string(k.voxelResolution)});
    return a;
}

}  // namespace

std::vector<AccuracySetting> accuracySweep(const SceneTraits& t, bool soft, int ambientOcclusionRays) {
    Knobs balanced;
    balanced.occlusionRays = ambientOcclusionRays;
    std::vector<AccuracySetting> sweep;
    auto add = [&](const std::string& knob, const std::string& value, double order, const Knobs& k) {
        sweep.push_back({knob, value, order, knobArgs(k, t, soft), false});
    };
    for (int n : {1, 2, 4, 8, 16}) {
        Knobs k = balanced;
        k.msaa = n;
        add("samples per pixel", std::to_string(n), n, k);
    }
    if (t.textured) {
        int i = 0;
        for (const char* f : {"nearest", "bilinear", "trilinear"}) {
            Knobs k = balanced;
            k.textureFilter = f;
            add("texture filter", f, i++, k);
        }
    }
    if (t.shadowed) {
        int i = 0;
        for (const char* m : {"none", "map", "hybrid", "raytraced", "auto"}) {
            Knobs k = balanced;
            k.shadows = m;
            add("shadow mode", m, i++, k);
        }
        for (const char* mode : {"map", "hybrid"})
            for (int size : {256, 512, 1024, 2048, 4096}) {
                Knobs k = balanced;
                k.shadows = mode;
                k.mapSizeTexels = size;
                add(std::string(mode) + " shadow-map size", std::to_string(size), size, k);
            }
    }
    if (t.threeD && ambientOcclusionRays > 0)
        for (int n : kOcclusionRaysSwept) {
            Knobs k = balanced;
            k.occlusionRays = n;
            add("ambient occlusion rays", std::to_string(n), n, k);
        }
    // What finds each sample's surface: the depth test, or camera rays through each structure
    // (the same image from each; the time differs). A voxel model's rays see its finest level of
    // solid voxels, where the rasterizer draws the level of detail's active faces.
    if (t.threeD || t.voxel) {
        const std::vector<const char*> structures = t.voxel ? std::vector<const char*>{"", "bvh", "kdtree", "octree", "bvh8"}
                                                            : std::vector<const char*>{"", "bvh", "grid"};
        for (size_t i = 0; i < structures.size(); ++i) {
            Knobs k = balanced;
            if (*structures[i]) k.renderer = "raytrace", k.accel = structures[i];
            add("renderer", *structures[i] ? std::string("raytrace, ") + structures[i] : std::string("raster"), double(i), k);
        }
    }
    if (t.threeD || t.voxel)
        for (bool reversed : {false, true}) {
            Knobs k = balanced;
            k.reversedDepth = reversed;
            add("depth precision", reversed ? "reversed" : "standard", reversed, k);
        }
    // Coarsest first; the finest is the balanced preset itself (no cap).
    for (size_t level = t.voxelResolutions.size(); level-- > 0;) {
        Knobs k = balanced;
        k.voxelResolution = level ? t.voxelResolutions[level] : 0;
        add("voxel resolution", std::to_string(t.voxelResolutions[level]), t.voxelResolutions[level], k);
    }
    if (t.voxel)
        for (float e : {8.0f, 4.0f, 2.0f, 1.0f, 0.5f, 0.25f}) {
            Knobs k = balanced;
            k.pixelError = e;
            add("LOD pixel error", formatNumber(e), e, k);
        }
    Knobs fast = balanced;
    fast.msaa = 1;
    fast.textureFilter = "nearest";
    fast.shadows = "map";
    fast.mapSizeTexels = 1024;
    fast.pixelError = 4.0f;
    fast.occlusionRays = std::min(ambientOcclusionRays, 1);
    add("preset", "fast", 0, fast);
    add("preset", "balanced", 1, balanced);
    Knobs exact = balanced;
    exact.msaa = 16;
    exact.shadows = "raytraced";
    exact.pixelError = 0.25f;
    exact.reversedDepth = true;
    exact.occlusionRays = ambientOcclusionRays > 0 ? kTruthOcclusionRays : 0;
    add("preset", "exact", 2, exact);
    sweep.push_back({"defaults", "defaults", 0, {}, true});  // what `render` does with no knob given
    Knobs truth;
    truth.occlusionRays = ambientOcclusionRays > 0 ? kTruthOcclusionRays : 0;
    truth.supersample = 16;
    truth.msaa = 1;
    truth.shadows = "raytraced";
    truth.pixelError = 0.0f;  // finest level, source triangles wherever the model keeps them
    truth.reversedDepth = true;  // the more precise depth
    add("ground truth", "256 samples", 0, truth);
    return sweep;
}

std::string settingId(const AccuracySetting& s) {
    std::string id;
    for (char c : s.knob + "-" + s.value) id += std::isalnum(static_cast<unsigned char>(c)) ? char(c) : '-';
    return id;
}

// ---------------------------------------------------------------------------------------------
// Running one setting

namespace {

void validate(const AccuracyOptions& o) {
    using scene::InputError;
    if (o.outDir.empty()) throw InputError("--out: a directory for the report is required");
    constexpr int kMaxSide = raster::kMaxFramebufferPixels / 16;  // the truth renders 16 times each side
    if (o.width < 8 || o.height < 8 || o.width > kMaxSide || o.height > kMaxSide)
        throw InputError("--width and --height: 8 to " + std::to_string(kMaxSide) +
                         " pixels (the ground truth renders 16 x 16 times as many)");
    if (o.frames < 1 || o.frames > 100) throw InputError("--frames: 1 to 100 runs per setting");
    if (o.threads < 0) throw InputError("--threads: must be 0 (all cores) or more");
}

bool isThreeD(const std::string& scene) {
    const scene::FileKind kind = scene::fileKindOf(scene);
    return kind != scene::FileKind::TriangleList && kind != scene::FileKind::VoxelModel;
}
bool isFile(const std::string& scene) { return scene.find('.') != std::string::npos || scene.find('/') != std::string::npos; }

std::string shellQuote(const std::string& s) {
    if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+") ==
                          std::string::npos)
        return s;
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// The command line of one run: the scene, its framing, the frame, the knobs, the outputs.
std::vector<std::string> renderArgs(const AccuracyOptions& o, const std::vector<std::string>& knobs,
                                    const fs::path& image, const fs::path& stats, int width, int height) {
    std::vector<std::string> a{o.executable.string(), "render", o.scene, "--width", std::to_string(width),
                               "--height", std::to_string(height), "--threads", std::to_string(o.threads)};
    if (isFile(o.scene) && scene::fileKindOf(o.scene) != scene::FileKind::TriangleList)
        a.insert(a.end(), {"--azimuth", formatNumber(o.azimuth), "--elevation", formatNumber(o.elevation)});
    if (o.cameraIndex >= 0) a.insert(a.end(), {"--camera-index", std::to_string(o.cameraIndex)});
    if (o.timeSeconds != 0.0f) a.insert(a.end(), {"--time", formatNumber(o.timeSeconds)});
    if (!o.animation.empty()) a.insert(a.end(), {"--animation", o.animation});
    a.insert(a.end(), knobs.begin(), knobs.end());
    a.insert(a.end(), {"--out", image.string(), "--stats", stats.string(), "--quiet"});
    return a;
}

// Runs argv as a child with stdout and stderr to `log`; its exit code. (Not its memory: on Linux
// wait4's ru_maxrss counts this process's resident set at the spawn too; a run reports its own.)
int runProcess(const std::vector<std::string>& argv, const fs::path& log) {
    std::vector<char*> cargv;
    for (const std::string& s : argv) cargv.push_back(const_cast<char*>(s.c_str()));
    cargv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, cargv[0], &actions, nullptr, cargv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(spawned));
    int status = 0;
    if (waitpid(pid, &status, 0) < 0) throw std::runtime_error("waiting for " + argv[0] + " failed");
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string readText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string joinCommandLine(const std::vector<std::string>& argv) {
    std::string line;
    for (size_t i = 0; i < argv.size(); ++i) line += (i ? " " : "") + shellQuote(i == 0 ? "cuberille" : argv[i]);
    return line;
}

// One run of `render`; a failure of the scene (exit 2) is the user's input error, repeated with
// the renderer's own message.
RunOutcome runOnce(const AccuracyOptions& o, const std::vector<std::string>& knobs, const fs::path& image,
                   const std::string& id, int width, int height) {
    const fs::path stats = o.outDir / "logs" / (id + ".json");
    const fs::path log = o.outDir / "logs" / (id + ".log");
    const std::vector<std::string> argv = renderArgs(o, knobs, image, stats, width, height);
    const int exitCode = runProcess(argv, log);
    RunOutcome r;
    r.commandLine = joinCommandLine(argv);
    if (exitCode != 0) {
        std::string message = readText(log);
        while (!message.empty() && message.back() == '\n') message.pop_back();
        const std::string what = "accuracy: `" + r.commandLine + "` failed (exit " + std::to_string(exitCode) +
                                 "): " + message;
        if (exitCode == 2) throw scene::InputError(what);
        throw std::runtime_error(what);
    }
    r.stats = nlohmann::json::parse(readText(stats));
    const nlohmann::json& j = r.stats;
    const nlohmann::json& t = j.at("timesMs");
    r.frameMs = t.at("frame").get<double>();
    r.setupMs = t.at("load").get<double>();
    if (j.contains("shadows")) {
        // The BVH (and for hybrid the edge adjacency) is built once per scene, before the first
        // frame's shadow stage.
        r.frameMs += j["shadows"].at("totalMs").get<double>();
        r.setupMs += j["shadows"].at("bvhBuildMs").get<double>() + j["shadows"].value("adjacencyMs", 0.0);
    }
    r.peakMib = j.at("process").at("peakResidentBytes").get<double>() / (1024.0 * 1024.0);  // the run's own VmHWM
    r.image = readImage(image);
    return r;
}

}  // namespace

SceneTraits probeScene(const AccuracyOptions& o) {
    SceneTraits t;
    t.voxel = scene::fileKindOf(o.scene) == scene::FileKind::VoxelModel;
    t.threeD = isThreeD(o.scene);
    std::vector<std::string> knobs;
    if (t.threeD) knobs = {"--shadows", "raytraced"};
    const fs::path image = o.outDir / "logs" / "probe.exr";
    const nlohmann::json j = runOnce(o, knobs, image, "probe", 64, 36).stats;
    t.textured = j.at("stages").at("shade").at("textureSamples").get<uint64_t>() > 0;
    t.shadowed = j.contains("shadows") && j["shadows"].at("lightsShadowed").get<uint64_t>() > 0;
    if (t.voxel) {
        const uint32_t finest = j.at("voxel").at("modelResolution").get<uint32_t>();
        const size_t levels = j.at("voxel").at("drawnPerLevel").size();
        for (size_t level = 0; level < levels; ++level) t.voxelResolutions.push_back(finest >> level);
    }
    fs::remove(image);
    return t;
}

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

AccuracyRow runSetting(const AccuracyOptions& o, const AccuracySetting& s, const std::string& id, int runs,
                       raster::Image& firstImage, raster::Image& lastImage) {
    AccuracyRow row;
    row.setting = s;
    row.id = id;
    std::vector<double> setup;
    for (int run = 0; run < runs; ++run) {
        const fs::path image = o.outDir / "renders" / (run == 0 ? id + ".exr" : id + ".again.exr");
        RunOutcome r = runOnce(o, s.args, image, id, o.width, o.height);
        if (run == 0) {
            row.commandLine = r.commandLine;
            firstImage = r.image;
        } else {
            row.deterministic = row.deterministic && r.image.rgba == firstImage.rgba;
            fs::remove(image);
        }
        row.frameMs.push_back(r.frameMs);
        setup.push_back(r.setupMs);
        row.peakMib = std::max(row.peakMib, r.peakMib);
        lastImage = std::move(r.image);
    }
    row.medianMs = median(row.frameMs);
    row.minMs = *std::min_element(row.frameMs.begin(), row.frameMs.end());
    row.maxMs = *std::max_element(row.frameMs.begin(), row.frameMs.end());
    row.setupMs = median(setup);
    return row;
}

void compareWithTruth(AccuracyRow& row, const raster::Image& image, const raster::Image& truth, const fs::path& outDir) {
    row.error = compareImages(image, truth);
    // The worst region: an eighth of the shorter side, shown magnified to about 160 pixels.
    const int side = std::max(8, std::min(image.width, image.height) / 8);
    row.worst = worstRegion(image, truth, side);
    const int scale = std::max(1, 160 / row.worst.width);
    writeImageAtomically(outDir / "crops" / (row.id + ".png"), comparisonCrop(image, truth, row.worst, scale));
    row.comparedWithTruth = true;
}

// A row is on the front when no other row is at least as fast and at least as accurate, and
// strictly better in one of the two (duplicates of one run count once).
void markParetoFront(std::vector<AccuracyRow>& rows) {
    for (AccuracyRow& r : rows) {
        r.pareto = true;
        for (const AccuracyRow& q : rows) {
            if (q.commandLine == r.commandLine) continue;
            const bool noWorse = q.medianMs <= r.medianMs && q.error.rmse <= r.error.rmse;
            const bool better = q.medianMs < r.medianMs || q.error.rmse < r.error.rmse;
            if (noWorse && better) {
                r.pareto = false;
                break;
            }
        }
    }
}

// Where theory says error must fall along a knob, check it on this scene, and say why it may not.
void checkMonotone(const std::vector<AccuracyRow>& rows, std::vector<std::string>& notes) {
    struct Expectation {
        const char* knob;
        bool errorFallsAsOrderRises;
        const char* whyItMayNot;
    };
    const Expectation expectations[] = {
        {"samples per pixel", true,
         "the sample patterns are not nested (the 8-sample pattern does not contain the 4-sample one), so more "
         "samples lower the expected error of an edge but not the error of every image"},
        {"map shadow-map size", true,
         "each size places texel centres differently, so a thin caster can fall between the texels of a larger "
         "map and onto those of a smaller one; the slope-scaled bias also scales with the texel"},
        {"hybrid shadow-map size", true,
         "the hybrid's error is the few marked-pixel misses of its map, which change with where texel centres "
         "fall rather than shrink with them"},
        {"ambient occlusion rays", true,
         "each pixel's rays are a fixed stratified set turned by its own angle, so a few more rays can move one "
         "pixel's estimate away from the truth; the error of the image falls as 1/N only in expectation"},
        {"voxel resolution", true,
         "a coarser level's colours and normals are averages, which can land nearer the supersampled truth over a "
         "region than a finer level's"},
        {"LOD pixel error", false,
         "a coarser level's voxel colours are averages, which can land nearer the supersampled truth over a "
         "region than a finer level's"},
    };
    for (const Expectation& e : expectations) {
        std::vector<const AccuracyRow*> curve;
        for (const AccuracyRow& r : rows)
            if (r.setting.knob == e.knob) curve.push_back(&r);
        if (curve.size() < 2) continue;
        std::sort(curve.begin(), curve.end(),
                  [](const AccuracyRow* a, const AccuracyRow* b) { return a->setting.order < b->setting.order; });
        std::string breaks;
        for (size_t i = 1; i < curve.size(); ++i) {
            const AccuracyRow& a = *curve[i - 1];
            const AccuracyRow& b = *curve[i];
            // Within 0.1% counts as flat: the steps theory orders are not the noise of a few pixels.
            constexpr double kFlat = 1e-3;
            const bool holds = e.errorFallsAsOrderRises ? b.error.rmse <= a.error.rmse * (1 + kFlat)
                                                        : b.error.rmse >= a.error.rmse * (1 - kFlat);
            if (!holds)
                breaks += std::string(breaks.empty() ? "" : "; ") + a.setting.value + " -> " + b.setting.value +
                          " (RMSE " + formatNumber(a.error.rmse) + " -> " + formatNumber(b.error.rmse) + ")";
        }
        const std::string direction = e.errorFallsAsOrderRises ? "falls as it rises" : "rises with it";
        if (breaks.empty())
            notes.push_back(std::string(e.knob) + ": error " + direction + " at every step (or stays within 0.1%), "
                            "as theory says.");
        else
            notes.push_back(std::string(e.knob) + ": error " + direction + " except at " + breaks + ". Why: " +
                            e.whyItMayNot + ".");
    }
    for (const AccuracyRow& r : rows)
        if (r.setting.knob == "ground truth")
            notes.push_back(r.error.rmse == 0.0 && r.deterministic
                                ? "ground truth: its runs are bit-identical (zero error against itself)."
                                : "ground truth: its runs DIFFER (RMSE " + formatNumber(r.error.rmse) +
                                      "); the renderer is not deterministic on this scene.");
}

void noteKnobsNotSwept(const SceneTraits& t, std::vector<std::string>& notes) {
    if (!t.threeD && !t.voxel)
        notes.push_back("texture filtering, shadows, depth precision and LOD: do not apply to a .tri scene (flat-coloured "
                        "window-space triangles); only samples per pixel is swept.");
    if (t.threeD && !t.textured) notes.push_back("texture filter: the scene samples no texture; not swept.");
    if (t.threeD && !t.shadowed) notes.push_back("shadows: the scene has no shadow-casting light; not swept.");
    if (t.voxel)
        notes.push_back("voxel resolution: swept over the model's own levels (--voxel-resolution); a finer model "
                        "than the file holds needs `cuberille voxelize --resolution` and is not swept here.");
}

std::string machineDescription() {
    std::ifstream in("/proc/cpuinfo");
    std::string line, model = "unknown CPU";
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            model = line.substr(line.find(':') + 2);
            break;
        }
    return model + ", " + std::to_string(raster::hardwareThreads()) + " hardware threads";
}

}  // namespace
}  // namespace cuberille::apps
