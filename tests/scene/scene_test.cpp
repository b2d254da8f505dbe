// Scene-level draw order: blended meshes go after opaque ones and back to front, whatever
// their order in the file.

#include <gtest/gtest.h>

#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/scene.h"

namespace cuberille::scene {
namespace {

Mesh quadAt(float z, glm::vec3 color, float alpha, raster::AlphaMode mode) {
    Mesh m;
    m.positions = {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}};
    m.normals.assign(4, glm::vec3(0, 0, 1));
    m.indices = {0, 1, 2, 0, 2, 3};
    m.color = color;
    m.alpha = alpha;
    m.alphaMode = mode;
    m.unlit = true;
    return m;
}

raster::Image render(const Scene& s) {
    raster::Pipeline p;
    raster::FramebufferDesc d;
    d.widthPixels = 16;
    d.heightPixels = 16;
    d.clearColor = s.background;
    p.beginFrame(d);
    s.draw(p, 1.0f);
    p.endFrame();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    return img;
}

TEST(SceneDraw, BlendedMeshesGoBackToFrontWhateverTheirOrder) {
    Scene s;
    s.camera.position = {0, 0, 5};
    s.camera.target = {0, 0, 0};
    s.background = {0, 0, 0, 1};
    const Mesh nearRed = quadAt(1.0f, {1, 0, 0}, 0.5f, raster::AlphaMode::Blend);
    const Mesh farBlue = quadAt(-1.0f, {0, 0, 1}, 0.5f, raster::AlphaMode::Blend);
    const Mesh opaqueGreen = quadAt(-2.0f, {0, 1, 0}, 1.0f, raster::AlphaMode::Opaque);
    s.meshes = {nearRed, farBlue, opaqueGreen};
    const raster::Image a = render(s);
    s.meshes = {opaqueGreen, farBlue, nearRed};
    const raster::Image b = render(s);
    EXPECT_EQ(a.rgba, b.rgba);
    // Green, then blue over it, then red over that: (0.5, 0.25, 0.25).
    const float* centre = a.pixel(8, 8);
    EXPECT_FLOAT_EQ(centre[0], 0.5f);
    EXPECT_FLOAT_EQ(centre[1], 0.25f);
    EXPECT_FLOAT_EQ(centre[2], 0.25f);
}

// A transmissive mesh (KHR_materials_transmission) goes after the opaque ones like a blended one,
// whatever the file's order, and without writing depth: the green quad behind a clear white glass
// shows through it (t = 1, metallic 0, no lights or ambient: exactly green x (1 - F(n.v)) at the
// centre, where the view is head-on and F = 0.04), as it does when the glass comes last.
TEST(SceneDraw, TransmissiveMeshesAreDrawnAfterTheOpaqueOnesAndShowThem) {
    Scene s;
    s.camera.position = {0, 0, 5};
    s.camera.target = {0, 0, 0};
    s.background = {0, 0, 0, 1};
    Mesh glass = quadAt(1.0f, {1, 1, 1}, 1.0f, raster::AlphaMode::Opaque);
    glass.unlit = false;
    glass.metallicRoughness = true;
    glass.metallic = 0.0f;
    glass.brdf.transmission = 1.0f;
    ASSERT_TRUE(glass.seeThrough());
    const Mesh opaqueGreen = quadAt(-2.0f, {0, 1, 0}, 1.0f, raster::AlphaMode::Opaque);
    s.meshes = {glass, opaqueGreen};
    const raster::Image a = render(s);
    s.meshes = {opaqueGreen, glass};
    const raster::Image b = render(s);
    EXPECT_EQ(a.rgba, b.rgba);
    const float* centre = a.pixel(8, 8);
    EXPECT_NEAR(centre[0], 0.0f, 1e-6f);
    EXPECT_NEAR(centre[1], 0.96f, 1e-4f) << "the view at the pixel centre is within 1/300 of head-on";
    EXPECT_NEAR(centre[2], 0.0f, 1e-6f);
}

}  // namespace
}  // namespace cuberille::scene
