// The `cuberille` command-line tool. Exit codes (DESIGN.md): 0 success, 1 failure while
// working, 2 bad usage or bad input.

#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "apps/render_command.h"
#include "scene/input_error.h"
#include "scene/procedural.h"

namespace {

constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;

void addRenderCommand(CLI::App& app, cuberille::apps::RenderOptions& o, std::string& view) {
    CLI::App* render = app.add_subcommand(
        "render", "Render one frame of a scene to an image (PNG: sRGB 8-bit; EXR: linear float)");
    std::string scenes;
    for (const auto& n : cuberille::scene::proceduralSceneNames()) scenes += " " + n;
    render->add_option("scene", o.scene,
                       "A .tri, .ply, .ply.gz, .obj, .gltf or .glb file, or a built-in scene:" + scenes)
        ->required();
    render->add_option("--width", o.width, "Image width in pixels")->capture_default_str();
    render->add_option("--height", o.height, "Image height in pixels")->capture_default_str();
    render->add_option("--msaa", o.msaa, "Samples per pixel: 1, 2, 4, 8 or 16")->capture_default_str();
    render->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
    render->add_option("--out", o.out, "Output image, .png or .exr")->required();
    render->add_option("--stats", o.statsPath, "Write per-stage counters and timings as JSON");
    render->add_option("--view", view, "What to show: color, depth, tiles (coarse block "
                                       "classes) or overdraw (depth-passing samples)")
        ->capture_default_str();
    render->add_option("--detail", o.detail, "Tessellation scale of built-in scenes")
        ->capture_default_str();
    render->add_option("--azimuth", o.azimuth, "Camera azimuth for mesh files, degrees about +y")
        ->capture_default_str();
    render->add_option("--elevation", o.elevation, "Camera elevation for mesh files, degrees")
        ->capture_default_str();
    render->add_option("--camera-index", o.cameraIndex,
                       "Use the file's N-th camera (glTF, in node order) instead of framing the model");
    render->add_option("--time", o.timeSeconds,
                       "glTF: pose the first animation at this time, in seconds (node transforms)")
        ->capture_default_str();
    render->add_option("--turntable", o.turntable,
                       "Write N frames turning around the scene (OUT_000.png, OUT_001.png, ...)");
    render->add_flag("--quiet", o.quiet, "Print nothing on success");
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"cuberille: a CPU renderer modelled on the GPU rasterization pipeline"};
    app.require_subcommand(1);
    cuberille::apps::RenderOptions renderOptions;
    std::string view = "color";
    addRenderCommand(app, renderOptions, view);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return kExitBadInput;
    }

    try {
        if (app.got_subcommand("render")) {
            renderOptions.view = cuberille::apps::parseView(view);
            return cuberille::apps::runRenderCommand(renderOptions);
        }
    } catch (const cuberille::scene::InputError& e) {
        std::fprintf(stderr, "cuberille: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cuberille: %s\n", e.what());
        return kExitFailure;
    }
    return 0;
}
