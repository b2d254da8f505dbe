// The renderer library (render/renderer.h) against the command line and against itself: the bytes
// `displayPixels` gives are the bytes the tool writes to a PNG, and a loaded scene renders a frame
// the same whatever it rendered before (another pose, camera, filter or size).

#include <cmath>
#include <filesystem>
#include <string>
#include <sys/wait.h>

#include <gtest/gtest.h>

#include "apps/png_file.h"
#include "render/renderer.h"
#include "scene/input_error.h"
#include "tests/scene/gltf_builder.h"
#include "tests/temp_paths.h"

namespace cuberille {
namespace {

namespace fs = std::filesystem;

std::vector<uint8_t> pngBytesAsRgba8(const fs::path& png) {
    const raster::Image image = apps::readPng(png);
    std::vector<uint8_t> bytes(image.rgba.size());
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t(std::lround(image.rgba[i] * 255.0f));
    return bytes;
}

class Renderer : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = testing::uniqueTempPath("renderer-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::create_directories(dir_);
        gltf_ = dir_ / "slide.gltf";
        testing::writeSlidingCubeGltf(gltf_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_, gltf_;
};

TEST_F(Renderer, DisplayPixelsAreTheBytesTheCliWritesToAPng) {
    struct Case {
        std::string arguments;
        render::FrameSettings settings;
    };
    std::vector<Case> cases(4);
    for (Case& c : cases) c.settings.width = 120, c.settings.height = 80;
    cases[0].arguments = "--msaa 4 --time 0.3";
    cases[0].settings.msaa = 4, cases[0].settings.timeSeconds = 0.3f;
    cases[1].arguments = "--shadows hybrid --camera-index 0 --time 0.6";
    cases[1].settings.shadows.mode = rt::ShadowMode::Hybrid, cases[1].settings.cameraIndex = 0, cases[1].settings.timeSeconds = 0.6f;
    cases[2].arguments = "--view depth --frustum-cull --zoom 2";
    cases[2].settings.view = render::View::Depth, cases[2].settings.frustumCull = true, cases[2].settings.zoom = 2.0f;
    cases[3].arguments = "--background 1,1,1,0 --msaa 8 --azimuth 200";
    cases[3].settings.background = glm::vec4(1, 1, 1, 0), cases[3].settings.msaa = 8, cases[3].settings.azimuth = 200.0f;
    const render::LoadedScene scene(gltf_.string());
    for (size_t i = 0; i < cases.size(); ++i) {
        const fs::path png = dir_ / ("cli" + std::to_string(i) + ".png");
        const std::string command = std::string(CUBERILLE_BINARY) + " render " + gltf_.string() + " --width 120 --height 80 " +
                                    cases[i].arguments + " --quiet --out " + png.string();
        const int status = std::system(command.c_str());
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
        const render::RenderResult r = render::render(scene, cases[i].settings);
        EXPECT_EQ(render::displayPixels(scene, cases[i].settings, r), pngBytesAsRgba8(png)) << cases[i].arguments;
    }
}

TEST_F(Renderer, ALoadedSceneRendersAFrameAsAFreshLoadDoes) {
    render::FrameSettings frame;
    frame.width = 96, frame.height = 64, frame.msaa = 4, frame.timeSeconds = 0.4f, frame.frustumCull = true;
    frame.shadows.mode = rt::ShadowMode::RayTraced;
    const render::LoadedScene fresh(gltf_.string());
    const raster::Image expected = render::render(fresh, frame).image;
    const render::LoadedScene reused(gltf_.string());
    render::FrameSettings other = frame;
    other.timeSeconds = 0.9f, other.azimuth = 100.0f, other.textureFilter = render::TextureFilterOverride::Nearest;
    other.width = 64, other.shadows.mode = rt::ShadowMode::Hybrid;
    render::render(reused, other);
    other.shadows.mode = rt::ShadowMode::RayTraced;
    render::render(reused, other);  // the shadow stage refitted to another pose
    EXPECT_EQ(render::render(reused, frame).image.rgba, expected.rgba);
}

TEST_F(Renderer, BadInputThrowsTheCliMessages) {
    EXPECT_THROW(render::LoadedScene("no-such-scene"), scene::InputError);
    const render::LoadedScene scene(gltf_.string());
    render::FrameSettings frame;
    frame.msaa = 3;
    try {
        render::render(scene, frame);
        FAIL() << "--msaa 3 was accepted";
    } catch (const scene::InputError& e) {
        EXPECT_STREQ(e.what(), "--msaa: 3 is not 1, 2, 4, 8 or 16");
    }
    frame.msaa = 1;
    frame.animation = "walk";
    EXPECT_THROW(render::render(scene, frame), scene::InputError);
}

}  // namespace
}  // namespace cuberille
