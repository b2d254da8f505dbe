#pragma once
// `cuberille batch JOBS.jsonl`: many renders in one process. Each line of the jobs file is one
// `render` as a JSON object: "scene" and "out" and any of render's options by their long names
// ("msaa": 4, "pixel-error": 2, "frustum-cull": true, "eye": [1, 2, 3]; underscores may stand for
// hyphens). Every scene is loaded once and reused by every job that names it with the same
// --detail and --up-axis. A job that fails is reported with its line number and the others go
// on; the exit code is 1 if any failed (2 if the jobs file itself cannot be read).

#include <filesystem>

#include <CLI/CLI.hpp>

#include "apps/render_command.h"

namespace cuberille::apps {

struct BatchOptions {
    std::filesystem::path jobs;
    bool quiet = false;
};

void addBatchCommand(CLI::App& app, BatchOptions& o);

int runBatchCommand(const BatchOptions& o);

/// One line of a jobs file as the render it names, checked as `render` checks it (checkRenderCommand);
/// throws scene::InputError with the message batch prints after the line's number.
RenderOptions parseBatchJob(const std::string& line, bool quiet);

}  // namespace cuberille::apps
