#pragma once
// `cuberille render`: a thin client of the renderer library (render/renderer.h). It loads the
// scene once, renders one frame or a sequence (--turntable, --animate), writes the images and
// the --stats JSON atomically and prints a summary.

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/image_io.h"
#include "render/display_image.h"
#include "render/frame_settings.h"
#include "render/renderer.h"

namespace cuberille::apps {

using render::RenderResult;
using render::TextureFilterOverride;
using render::View;
using render::clearColorFor;
using render::kFarthestGrey;
using render::kNearestGrey;
using render::legibleDepth;
using render::parseBackground;
using render::parseBvhUpdate;
using render::parseDepthConvention;
using render::parseTextureFilter;
using render::parseVector3;
using render::parseView;
using render::textureFilterName;
using render::validateFrameOptions;

/// The render command's options: a frame's settings, how the scene is read, and what the tool
/// does with files and sequences.
struct RenderOptions : render::FrameSettings {
    std::string scene;  // a .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox path, or a built-in scene name
    float detail = 1.0f;      // tessellation scale of built-in scenes
    bool zUp = false;         // --up-axis z: mesh files whose up is +z are turned to +y on load
    int turntable = 0;        // > 0: that many frames around the scene, OUT_000.ext ...
    int animate = 0;          // glTF, > 0: that many frames of the animation from --time, OUT_000.ext ...
    float fps = 30.0f;        // --animate: frames a second of animation time
    /// --shadow-focus; unset (auto): MapFocus::Scene for --turntable, whose camera circles still
    /// lights and casters (the sun's map is then drawn once), else View.
    std::optional<rt::MapFocus> shadowFocus;
    std::filesystem::path out;
    std::filesystem::path statsPath;
    bool quiet = false;
    int pngBits = 8;  // --png-bits 8|16
};

/// How a render's images are written: alpha when the background is not opaque, --png-bits.
ImageWriteOptions imageWriteOptions(const RenderOptions& o);

/// The scene of a render command, loaded with its warnings printed to stderr unless quiet.
render::LoadedScene loadScene(const RenderOptions& options);

/// Loads the scene and renders one frame; throws scene::InputError for bad input. The frame's
/// loadMs includes the scene's read.
RenderResult renderScene(const RenderOptions& options);

nlohmann::json statsToJson(const RenderOptions& options, const RenderResult& result);

/// The whole subcommand: render, write the image and stats, print a summary. Returns the
/// exit code.
int runRenderCommand(const RenderOptions& options);
/// The same with the scene already loaded (options.scene, .detail and .zUp as it was loaded with)
/// and the options already checked by checkRenderCommand (batch checks each job before loading).
int runRenderCommand(const RenderOptions& options, const render::LoadedScene& scene);
/// How many frames the command writes: --turntable's or --animate's count, or 1.
int frameCount(const RenderOptions& options);
/// The file frame `index` is written to: --out itself for one frame, OUT_007.png in a sequence.
std::filesystem::path frameFile(const RenderOptions& options, int index);
/// Frames [first, first + count) of the command, rendered and written (atomically) as the whole
/// command writes them, quietly; returns each frame's --stats object in order. A frame's image
/// never depends on the frames before it (render/loaded_scene.h), so any split of a sequence into
/// runs writes the same files: what a distributed run (python/cuberille/dask) relies on.
nlohmann::json renderFrameRun(const render::LoadedScene& scene, const RenderOptions& options, int first, int count);
/// The --stats file from every frame's object in order: the one object, or {"frames": [...]}.
void writeRenderStats(const RenderOptions& options, const nlohmann::json& frames);
/// What the command refuses before any work: no --out, an unwritable output, a bad sequence.
void checkRenderCommand(const RenderOptions& options);

}  // namespace cuberille::apps
