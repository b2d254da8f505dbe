// Golden images: exact comparison against reference_images/. On a mismatch the test writes the
// rendered image and a diff image (|difference| x 16, red where channels differ) beside the
// build, and names them. Regenerate with `make golden` (CUBERILLE_UPDATE_GOLDEN=1).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "apps/image_io.h"
#include "apps/render_command.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/tri_scene.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

// A fixed scene exercising overlaps, shared edges, slivers, sub-pixel and clipped triangles.
scene::TriScene goldenTriScene() {
    return scene::parseTriScene(R"(
# overlapping colours, drawn in order
4 4 90 10 20 60  0.9 0.2 0.1
30 8 95 55 10 58  0.1 0.6 0.9
# a quad split on its diagonal (shared edge)
50 30 90 30 90 58 0.8 0.8 0.2
50 30 90 58 50 58 0.2 0.8 0.3
# slivers and sub-pixel triangles
2 62 95 60.5 95 61 1
10 40.2 10.6 40.9 10.1 41.3 1
11.3 41.1 12.1 41.4 11.7 42.3 1
# far outside, clipped by the guard band
-50000 -40000 80000 20 -60 50000 0.05 0.05 0.3
)", "golden.tri");
}

fs::path referencePath(const std::string& name) {
    return fs::path(CUBERILLE_SOURCE_DIR) / "reference_images" / (name + ".exr");
}

void compareWithGolden(const std::string& name, const raster::Image& image) {
    const fs::path ref = referencePath(name);
    if (std::getenv("CUBERILLE_UPDATE_GOLDEN")) {
        apps::writeImageAtomically(ref, image);
        GTEST_SKIP() << "updated " << ref;
    }
    ASSERT_TRUE(fs::exists(ref)) << ref << " is missing; run `make golden`";
    const raster::Image expected = apps::readImage(ref);
    ASSERT_EQ(expected.width, image.width);
    ASSERT_EQ(expected.height, image.height);
    size_t differing = 0;
    raster::Image diff = image;
    for (size_t i = 0; i < image.rgba.size(); i += 4) {
        bool differs = false;
        for (int c = 0; c < 4; ++c) {
            const float d = std::abs(image.rgba[i + c] - expected.rgba[i + c]);
            differs = differs || image.rgba[i + c] != expected.rgba[i + c];
            diff.rgba[i + c] = std::min(1.0f, d * 16.0f);
        }
        if (differs) diff.rgba[i] = 1.0f, diff.rgba[i + 3] = 1.0f;
        differing += differs;
    }
    if (differing) {
        const fs::path dir = fs::current_path() / "golden_failures";
        fs::create_directories(dir);
        apps::writeImageAtomically(dir / (name + ".actual.exr"), image);
        apps::writeImageAtomically(dir / (name + ".diff.png"), diff);
        FAIL() << name << ": " << differing << " pixels differ; see " << (dir / (name + ".diff.png"));
    }
}

raster::Image renderTri(const scene::TriScene& s, int samples, bool tiles) {
    raster::Pipeline p;
    raster::FramebufferDesc d;
    d.widthPixels = 100;
    d.heightPixels = 66;
    d.samples = samples;
    d.recordBlockClasses = tiles;
    p.beginFrame(d);
    p.draw(s.drawCall());
    p.endFrame();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    if (tiles) {
        const raster::Image color = img;
        raster::visualizeBlockClasses(p.framebuffer(), color, img);
    }
    return img;
}

TEST(Golden, TriSceneAt1Sample) { compareWithGolden("tri_msaa1", renderTri(goldenTriScene(), 1, false)); }
TEST(Golden, TriSceneAt4Samples) { compareWithGolden("tri_msaa4", renderTri(goldenTriScene(), 4, false)); }
TEST(Golden, TriSceneAt16Samples) { compareWithGolden("tri_msaa16", renderTri(goldenTriScene(), 16, false)); }
TEST(Golden, TriSceneTilesView) { compareWithGolden("tri_tiles", renderTri(goldenTriScene(), 4, true)); }

raster::Image renderField(int msaa, apps::View view) {
    apps::RenderOptions o;
    o.scene = "field";
    o.width = 160;
    o.height = 100;
    o.msaa = msaa;
    o.detail = 0.1f;
    o.view = view;
    return apps::renderScene(o).image;
}

TEST(Golden, FieldSceneLambertAt4Samples) {
    compareWithGolden("field_msaa4", renderField(4, apps::View::Color));
}
TEST(Golden, FieldSceneDepthView) {
    compareWithGolden("field_depth", renderField(1, apps::View::Depth));
}

}  // namespace
}  // namespace cuberille::testing
