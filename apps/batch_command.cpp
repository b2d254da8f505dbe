#include "apps/batch_command.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/progress.h"
#include "apps/render_options_cli.h"
#include "raster/clock.h"
#include "scene/input_error.h"

namespace cuberille::apps {
namespace {

std::vector<std::string> renderArguments(const nlohmann::json& job);

// A job's key as render's long option: "pixel_error" and "pixel-error" are --pixel-error.
std::string optionName(std::string key) {
    std::replace(key.begin(), key.end(), '_', '-');
    return key;
}

// Scenes by what they were loaded from and how: a job reuses one loaded for an earlier job.
using SceneKey = std::tuple<std::string, float, bool>;

}  // namespace

void addBatchCommand(CLI::App& app, BatchOptions& o) {
    CLI::App* batch = app.add_subcommand(
        "batch", "Run many renders in one process: one JSON object per line of JOBS ({\"scene\": ..., \"out\": ..., "
                 "and render's options by name}); each scene is loaded once");
    batch->add_option("jobs", o.jobs, "A JSON-lines file of render jobs (blank lines and lines starting with # are skipped)")
        ->required();
    batch->add_flag("--quiet", o.quiet, "Print only failures");
}

int runBatchCommand(const BatchOptions& o) {
    std::ifstream in(o.jobs);
    if (!in) throw scene::InputError(o.jobs.string() + ": cannot open file");
    std::map<SceneKey, std::unique_ptr<render::LoadedScene>> scenes;
    int jobs = 0, failed = 0;
    const double t0 = raster::nowMs();
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    ProgressLine progress("line", int(lines.size()), o.quiet);
    for (int number = 1; number <= int(lines.size()); ++number) {
        const std::string& line = lines[size_t(number) - 1];
        progress.update(number);
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
        ++jobs;
        try {
            const RenderOptions job = parseBatchJob(line, o.quiet);
            std::unique_ptr<render::LoadedScene>& scene = scenes[{job.scene, job.detail, job.zUp}];
            if (!scene) scene = std::make_unique<render::LoadedScene>(loadScene(job));
            runRenderCommand(job, *scene);
        } catch (const std::exception& e) {
            ++failed;
            progress.finish();
            std::fprintf(stderr, "cuberille batch: %s:%d: %s\n", o.jobs.c_str(), number, e.what());
        }
    }
    progress.finish();
    if (!o.quiet)
        std::printf("batch: %d job%s, %d failed, %zu scene%s loaded; %.1f ms\n", jobs, jobs == 1 ? "" : "s", failed,
                    scenes.size(), scenes.size() == 1 ? "" : "s", raster::nowMs() - t0);
    return failed > 0 ? 1 : 0;
}

// A job line parsed by the render command's own options (apps/render_options_cli.h), so it takes
// what `render` takes and is refused as `render` would refuse it.
RenderOptions parseBatchJob(const std::string& line, bool quiet) {
    nlohmann::json job;
    try {
        job = nlohmann::json::parse(line);
    } catch (const nlohmann::json::parse_error& e) {
        throw scene::InputError(std::string("not a JSON object: ") + e.what());
    }
    if (!job.is_object()) throw scene::InputError("not a JSON object");
    if (!job.contains("scene") || !job["scene"].is_string()) throw scene::InputError("\"scene\": a string is required");
    {  // a key render has no option for is named as the job's, not as CLI11's "extra argument"
        CLI::App app;
        RenderOptions unused;
        RenderNames unusedNames;
        const CLI::App* render = addRenderCommand(app, unused, unusedNames);
        for (const auto& [key, value] : job.items()) {
            const std::string name = optionName(key);
            bool known = key == "scene";
            for (const CLI::Option* option : render->get_options())
                for (const std::string& n : option->get_lnames()) known = known || n == name;
            if (!known) throw scene::InputError("\"" + key + "\": render has no option --" + name);
        }
    }
    RenderOptions o = parseRenderArguments(renderArguments(job));
    o.quiet = o.quiet || quiet;
    checkRenderCommand(o);
    return o;
}

namespace {

// The job as `render`'s arguments on a command line: the scene, then each option.
std::vector<std::string> renderArguments(const nlohmann::json& job) {
    std::vector<std::string> arguments{job["scene"].get<std::string>()};
    for (const auto& [key, value] : job.items()) {
        if (key == "scene") continue;
        const std::string option = "--" + optionName(key);
        if (value.is_boolean()) {  // a flag, set either way: "legend": false turns a default-on flag off
            arguments.push_back(option + (value.get<bool>() ? "=true" : "=false"));
            continue;
        }
        std::string text;
        if (value.is_string()) {
            text = value.get<std::string>();
        } else if (value.is_number()) {
            text = value.dump();
        } else if (value.is_array()) {
            for (const auto& item : value) {
                if (!item.is_number()) throw scene::InputError("\"" + key + "\": an array of numbers, or a string");
                text += (text.empty() ? "" : ",") + item.dump();
            }
        } else {
            throw scene::InputError("\"" + key + "\": a string, number, true/false or array of numbers");
        }
        arguments.push_back(option);
        arguments.push_back(text);
    }
    return arguments;
}

}  // namespace
}  // namespace cuberille::apps
