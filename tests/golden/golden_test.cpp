// Golden images: exact comparison against reference_images/. On a mismatch the test writes the
// rendered image and a diff image (|difference| x 16, red where channels differ) beside the
// build, and names them. Regenerate with `make golden` (CUBERILLE_UPDATE_GOLDEN=1).

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "apps/explain_command.h"
#include "apps/image_io.h"
#include "apps/png_file.h"
#include "apps/render_command.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/tri_scene.h"
#include "tests/scene/gltf_builder.h"
#include "tests/voxel/voxel_test_support.h"
#include "lod/lod_pyramid.h"
#include "voxel/cvox_file.h"
#include "tests/temp_paths.h"

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
        const fs::path dir = fs::path(CUBERILLE_BUILD_DIR) / "golden_failures";
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

raster::Image renderField(int msaa, apps::View view, int occlusionRays = 0) {
    apps::RenderOptions o;
    o.scene = "field";
    o.width = 160;
    o.height = 100;
    o.msaa = msaa;
    o.detail = 0.1f;
    o.view = view;
    o.ambientOcclusion.raysPerPixel = occlusionRays;
    return apps::renderScene(o).image;
}

TEST(Golden, FieldSceneLambertAt4Samples) {
    compareWithGolden("field_msaa4", renderField(4, apps::View::Color));
}
// Ambient occlusion by rays (rt/ambient_occlusion.h) darkening the field's ambient light between
// its spheres, tori and ground: the estimator's directions, per-pixel turn and offset are in
// these bits.
TEST(Golden, FieldSceneWithAmbientOcclusion) {
    compareWithGolden("field_ao8", renderField(4, apps::View::Color, 8));
}
// The depth view's distances along the view axis (world units), alpha the coverage.
TEST(Golden, FieldSceneDepthView) {
    compareWithGolden("field_depth", renderField(1, apps::View::Depth));
}

// The default scene: a generated texture, metallic-roughness and Lambert materials, blending,
// alpha masking, a sun and a point light.
TEST(Golden, DemoSceneAt4Samples) {
    apps::RenderOptions o;
    o.scene = "demo";
    o.width = 192;
    o.height = 108;
    o.msaa = 4;
    o.detail = 0.2f;
    compareWithGolden("demo_msaa4", apps::renderScene(o).image);
}

// A glTF file the test writes itself, seen through its own camera: a node hierarchy, a textured
// metallic-roughness ground (texture image beside the file, REPEAT and a KHR_texture_transform
// scale), a BLEND quad over an alpha-MASK cut-out (double-sided), a two-joint skin bent at
// its joint, a morph target at weight 0.75, and a KHR_lights_punctual spot light.
fs::path writeGoldenGltf(const fs::path& dir) {
    fs::create_directories(dir);
    // An 8x8 RGBA checker whose alpha cuts out every other 2x2 block (PNG, sRGB bytes).
    std::vector<uint8_t> checker;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const uint8_t v = (x + y) % 2 ? 230 : 110;
            checker.insert(checker.end(), {v, uint8_t(v * 0.9f), uint8_t(v * 0.7f), uint8_t((x / 2 + y / 2) % 2 ? 255 : 0)});
        }
    apps::writePng8(dir / "checker.png", 8, 8, 4, checker);

    GltfBuilder b;
    auto& j = b.json();
    j["extensionsUsed"] = {"KHR_lights_punctual", "KHR_texture_transform"};
    j["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"type", "spot"}, {"intensity", 60}, {"color", {1.0, 0.9, 0.8}}, {"spot", {{"outerConeAngle", 0.9}}}}};
    b.push("images", {{"uri", "checker.png"}});
    b.push("samplers", {{"magFilter", 9728}, {"minFilter", 9987}});
    b.push("textures", {{"source", 0}, {"sampler", 0}});
    const std::vector<glm::vec3> quadNormals(4, glm::vec3(0, 1, 0));
    const std::vector<glm::vec2> quadUvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const int quadIndices = b.indices({0, 3, 2, 0, 2, 1});  // counter-clockwise from +y
    auto quad = [&](float half) {
        return b.positions({{-half, 0, -half}, {half, 0, -half}, {half, 0, half}, {-half, 0, half}});
    };
    const int normals = b.vec3s(quadNormals), uvs = b.vec2s(quadUvs);
    // Materials: 0 textured ground, 1 blended red, 2 masked cut-out, 3 plain.
    b.push("materials", {{"pbrMetallicRoughness",
                          {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {3, 3}}}}}}}},
                           {"metallicFactor", 0.0}, {"roughnessFactor", 0.6}}}});
    b.push("materials", {{"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 0.1, 0.1, 0.5}}, {"metallicFactor", 0.0}}},
                         {"alphaMode", "BLEND"}});
    b.push("materials", {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}}},
                         {"alphaMode", "MASK"}, {"doubleSided", true}});
    b.push("materials", {{"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.5, 0.9, 1.0}}, {"metallicFactor", 0.3},
                                                  {"roughnessFactor", 0.4}}}});
    auto primitive = [&](int position, int material) {
        return nlohmann::json{{"attributes", {{"POSITION", position}, {"NORMAL", normals}, {"TEXCOORD_0", uvs}}},
                              {"indices", quadIndices}, {"material", material}};
    };
    b.push("meshes", {{"primitives", {primitive(quad(3.0f), 0)}}});  // 0 ground
    b.push("meshes", {{"primitives", {primitive(quad(0.8f), 1)}}});  // 1 blended
    b.push("meshes", {{"primitives", {primitive(quad(0.8f), 2)}}});  // 2 cut-out
    // 3: a strip of two cells up +y, the upper row bound to joint 1.
    const int stripPositions = b.positions({{-0.2f, 0, 0}, {0.2f, 0, 0}, {-0.2f, 1, 0}, {0.2f, 1, 0}, {-0.2f, 2, 0}, {0.2f, 2, 0}});
    const int stripJoints = b.joints(std::vector<glm::u8vec4>(6, glm::u8vec4(0, 1, 0, 0)));
    const int stripWeights = b.vec4s({{1, 0, 0, 0}, {1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}, {0.5f, 0.5f, 0, 0}, {0, 1, 0, 0}, {0, 1, 0, 0}});
    b.push("meshes", {{"primitives", {{{"attributes", {{"POSITION", stripPositions}, {"JOINTS_0", stripJoints}, {"WEIGHTS_0", stripWeights}}},
                                       {"mode", 5}, {"material", 3}}}}});
    const int inverseBinds = b.mat4s({glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(0, -1, 0))});
    // 4: a triangle whose morph target lifts its apex.
    const int morphBase = b.positions({{-0.5f, 0, 0}, {0.5f, 0, 0}, {0, 0.5f, 0}});
    const int morphDelta = b.positions({{0, 0, 0}, {0, 0, 0}, {0, 1, 0}});
    b.push("meshes", {{"primitives", {{{"attributes", {{"POSITION", morphBase}}}, {"targets", {{{"POSITION", morphDelta}}}},
                                       {"material", 3}}}},
                      {"weights", {0.75}}});
    // Nodes: 0 root (rotated 20° about y), children ground, blended, cut-out, skin root, morph.
    const float s = std::sin(glm::radians(10.0f)), c = std::cos(glm::radians(10.0f));
    b.push("nodes", {{"rotation", {0, s, 0, c}}, {"children", {1, 2, 3, 4, 7, 8}}});
    b.push("nodes", {{"mesh", 0}});
    b.push("nodes", {{"mesh", 1}, {"translation", {0.5, 0.8, 1.2}}, {"rotation", {0.5, 0, 0, 0.8660254}}});
    b.push("nodes", {{"mesh", 2}, {"translation", {-1.2, 1.0, -1.0}}, {"rotation", {0.7071068, 0, 0, 0.7071068}}});
    b.push("nodes", {{"mesh", 3}, {"skin", 0}});
    b.push("nodes", {{"translation", {1.5, 0, -0.5}}, {"children", {6}}});  // 5 joint 0
    b.push("nodes", {{"translation", {0, 1, 0}}, {"rotation", {0, 0, -0.3826834, 0.9238795}}});  // 6 joint 1, bent 45°
    b.push("nodes", {{"mesh", 4}, {"translation", {-1.5, 0.01, 1.0}}});
    b.push("nodes", {{"translation", {0, 4, 0}}, {"rotation", {-0.7071068, 0, 0, 0.7071068}},
                     {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});  // 8 spot, pointing down
    b.push("skins", {{"joints", {5, 6}}, {"inverseBindMatrices", inverseBinds}});
    j["nodes"][0]["children"].push_back(5);
    b.push("cameras", {{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}, {"zfar", 50}}}});
    b.push("nodes", {{"camera", 0}, {"translation", {0, 3.5, 6}}, {"rotation", {-0.2588190, 0, 0, 0.9659258}}});  // 9
    j["scenes"] = {{{"nodes", {0, 9}}}};
    j["scene"] = 0;
    b.write(dir / "golden.gltf");
    return dir / "golden.gltf";
}

TEST(Golden, ProceduralGltfThroughItsCamera) {
    const fs::path dir = cuberille::testing::uniqueTempPath("golden-gltf");
    apps::RenderOptions o;
    o.scene = writeGoldenGltf(dir).string();
    o.width = 160;
    o.height = 120;
    o.msaa = 4;
    o.cameraIndex = 0;
    const raster::Image image = apps::renderScene(o).image;
    fs::remove_all(dir);
    compareWithGolden("gltf_procedural", image);
}

// A voxel model made here: two coloured spheres voxelized at 128³ with their LOD pyramid, rendered
// through `render model.cvox` in colour (4 samples, the finest level) and in the LOD view at a
// pixel error that selects the coarser level.
fs::path goldenVoxelModel() {
    const fs::path path = cuberille::testing::uniqueTempPath("golden.cvox");
    std::mt19937 rng(31);
    auto tris = icosphere(3, glm::dvec3(0.0), 2.0, randomRotation(rng));
    const auto small = icosphere(2, glm::dvec3(2.6, 0.8, 0.5), 0.9, randomRotation(rng));
    tris.insert(tris.end(), small.begin(), small.end());
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i)
        colors.push_back(glm::vec3(0.3f + 0.6f * float(i % 5) / 4.0f, 0.4f, 0.9f - 0.6f * float(i % 7) / 6.0f));
    voxel::VoxelizeOptions o;
    o.resolution = 128;
    voxel::VoxelModel m = voxel::voxelizeMesh(*viewOf(tris, 200, colors), o);
    lod::buildLodPyramid(m, {});
    std::ofstream out(path, std::ios::binary);
    voxel::writeCvox(m, out);
    return path;
}

raster::Image renderVoxels(apps::View view, int msaa, float pixelError) {
    const fs::path model = goldenVoxelModel();
    apps::RenderOptions o;
    o.scene = model.string();
    o.width = 160;
    o.height = 100;
    o.msaa = msaa;
    o.view = view;
    o.pixelError = pixelError;
    o.quiet = true;
    raster::Image image = apps::renderScene(o).image;
    fs::remove(model);
    return image;
}

TEST(Golden, VoxelModelAt4Samples) { compareWithGolden("voxels_msaa4", renderVoxels(apps::View::Color, 4, 1.0f)); }
TEST(Golden, VoxelModelLodView) { compareWithGolden("voxels_lod", renderVoxels(apps::View::Lod, 1, 3.2f)); }


// `cuberille explain` for the triangle docs/pipeline.md walks through: every stage's picture.
// These are the pictures in docs/images/pipeline (`make pipeline-docs` writes them from the
// same call), so a change to a stage that moves a picture fails here until both are renewed.
TEST(Golden, ExplainStagesOfTheDocumentedTriangle) {
    apps::ExplainOptions o;
    const apps::ExplainResult r = apps::explainScene(scene::parseTriScene(std::string(apps::kExplainTriangle) + " 1\n", "--triangle"), o);
    ASSERT_EQ(r.images.size(), 12u);
    for (const auto& [name, image] : r.images) {
        SCOPED_TRACE(name);
        compareWithGolden("explain_" + name, image);
    }
}

}  // namespace
}  // namespace cuberille::testing
