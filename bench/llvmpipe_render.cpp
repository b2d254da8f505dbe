// The peer of `cuberille render` as a whole process, for bench/process_bench: read a model file
// (with Cuberille's loaders: the peer has none of its own), draw one frame with llvmpipe
// (bench/llvmpipe_peer.h), write a PNG. What a server that renders thumbnails with Mesa does.

#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/png_file.h"
#include "bench/llvmpipe_peer.h"
#include "scene/model_scene.h"

int main(int argc, char** argv) {
    using namespace cuberille;
    CLI::App app{"Render a model file with Mesa's llvmpipe into a PNG"};
    std::string file, out;
    int width = 640, height = 480, msaa = 1;
    app.add_option("file", file)->required();
    app.add_option("--out", out)->required();
    app.add_option("--width", width);
    app.add_option("--height", height);
    app.add_option("--msaa", msaa);
    CLI11_PARSE(app, argc, argv);
    try {
        const scene::Scene s = scene::loadModelScene(file, {}, [](const std::string&) {});
        bench::LlvmpipePeer peer(width, height, msaa);
        peer.upload(s);
        peer.renderFrame(s);
        const std::vector<unsigned char>& rgba = peer.pixels();
        std::vector<uint8_t> rgb(size_t(width) * height * 3);
        for (int y = 0; y < height; ++y)  // OpenGL's rows run bottom-up
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    rgb[(size_t(y) * width + x) * 3 + c] = rgba[(size_t(height - 1 - y) * width + x) * 4 + c];
        apps::writePng8(out, width, height, 3, rgb);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "llvmpipe_render: %s\n", e.what());
        return 1;
    }
    return 0;
}
