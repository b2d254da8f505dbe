#pragma once
// The render command's options as CLI11 reads them: shared by `cuberille render` and the jobs of
// `cuberille batch` (apps/batch_command.h), so a job line takes exactly the options `render` does,
// with the same checks and messages.

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/render_command.h"

namespace cuberille::apps {

/// A subcommand's arguments as a command line gives them (without the subcommand's name), read by
/// the parser `addCommand` adds to an empty app, as the tool reads its own command line; a parse
/// error throws scene::InputError with CLI11's message. How a program that drives the tool's work,
/// such as the distributed runner (python/cuberille/dask), reads the command it was given.
void parseSubcommandArguments(const std::string& name, const std::vector<std::string>& arguments,
                              const std::function<void(CLI::App&)>& addCommand);

/// The frame's size, samples and the worker threads, as every rendering command takes them.
void addFrameOptions(CLI::App* command, int& width, int& height, int& msaa, int& threads);

/// The render options parsed from names after CLI11 has read them.
struct RenderNames {
    std::string view = "color", shadows = "none", shadowFocus = "auto", textureFilter = "file", depth = "standard", bvhUpdate = "refit", accel = "bvh", renderer = "raster", frameVisibility = "auto";
    std::string eye, target, up, upAxis = "y", background;
    float fovDegrees = 0.0f;
};

/// Adds the `render` subcommand, whose options fill `o` and `names`.
CLI::App* addRenderCommand(CLI::App& app, RenderOptions& o, RenderNames& names);

/// The options read as names (--view, --shadows, --eye, ...) turned into `o`'s values; throws
/// scene::InputError naming the option.
void applyRenderNames(const RenderNames& names, RenderOptions& o);

/// `render`'s arguments as a command line gives them (the scene and options, without "render"),
/// parsed and turned into options by the command's own parser; throws scene::InputError with the
/// message the command prints. How a program that drives the tool's work, such as the distributed
/// runner (python/cuberille/dask), reads the command it was given.
RenderOptions parseRenderArguments(const std::vector<std::string>& arguments);

}  // namespace cuberille::apps
